// A DE sample test (sample.h): the sample's region and packing, and the
// run (SampleRun, sample_run.h and sample_measure.cpp).
#include "sample_run.h"

namespace dembridge::demo
{
using namespace dembridge::dem;


Region sample_region(const SampleConfig& cfg)
{
  if (cfg.shape == "cylinder")
    return cylinder_region({0.0, 0.0, 0.0}, 0.5 * cfg.diameter, cfg.height);
  if (cfg.shape == "prism")
    return box_region({0.0, 0.0, 0.0}, {cfg.diameter, cfg.diameter, cfg.height});
  throw std::runtime_error("shape '" + cfg.shape + "': allowed are cylinder, prism");
}

Packing sample_packing(const SampleConfig& cfg)
{
  if (!cfg.packing_file.empty())
  {
    Packing p = read_packing(cfg.packing_file);
    check_packing_fits(sample_region(cfg), p, "--packing " + cfg.packing_file);
    return p;
  }
  PackingOptions po;
  po.mean_radius = cfg.mean_radius;
  po.radius_ratio = cfg.radius_ratio;
  po.seed = cfg.seed;
  return generate_packing(sample_region(cfg), po);
}

nlohmann::json run_sample(const SampleConfig& cfg) { return sample_detail::SampleRun(cfg).run(); }

} // namespace dembridge::demo
