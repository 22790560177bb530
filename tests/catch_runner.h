#pragma once

namespace dembridge::tests
{
/// Runs the Catch2 session over the command line (test filters, reporters).
int run_catch(int argc, char* argv[]);
} // namespace dembridge::tests
