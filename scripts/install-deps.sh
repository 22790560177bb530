#!/bin/sh
# Installs the Debian 12 packages dembridge needs, only those missing.
# With --test, also those the test suite needs (ParaView and its Python
# support, python3-paraview, whose pvpython
# opens every XDMF kind the programs write).
# Run as root (or through sudo); non-interactive; does nothing when all are there.
set -eu
PKGS="cmake make g++ pkg-config libdolfinx-dev python3-ffcx libpetsc-real-dev
libeigen3-dev catch2 libhdf5-mpi-dev libcli11-dev libspdlog-dev nlohmann-json3-dev
python3-matplotlib python3-h5py libtomlplusplus-dev libgmsh-dev"
[ "${1:-}" = "--test" ] && PKGS="$PKGS paraview python3-paraview"
missing=""
for p in $PKGS; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing="$missing $p"
done
[ -z "$missing" ] && exit 0
echo "dembridge: installing missing Debian packages:$missing"
if [ "$(id -u)" -ne 0 ]; then
  SUDO=sudo
else
  SUDO=""
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
# shellcheck disable=SC2086
$SUDO apt-get install -y -qq --no-install-recommends $missing
