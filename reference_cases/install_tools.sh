#!/usr/bin/env bash
# Install the reference tools (OpenFOAM v1912 and LIGGGHTS 3.8.0, Debian 12 packages).
# Idempotent: does nothing when interFoam, liggghts and mpirun are already installed.
# Needs root (or sudo). Used by CI before `make test`.
set -euo pipefail

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    SUDO="sudo"
fi

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }

need_foam=0; need_dem=0
installed openfoam && installed openmpi-bin || need_foam=1
installed liggghts && installed openmpi-bin || need_dem=1

if [ "$need_foam" -eq 0 ] && [ "$need_dem" -eq 0 ]; then
    echo "install_tools: openfoam, liggghts, openmpi-bin already installed"
    exit 0
fi

export DEBIAN_FRONTEND=noninteractive
# apt-get update only if the package lists are missing or older than a day
if [ -z "$(find /var/lib/apt/lists -maxdepth 1 -name '*_Packages*' -mmin -1440 2>/dev/null | head -1)" ]; then
    $SUDO apt-get update
fi
if [ "$need_foam" -eq 1 ]; then
    # pulls in openfoam-examples (tutorials); about 480 MB
    $SUDO apt-get install -y openfoam openmpi-bin
fi
if [ "$need_dem" -eq 1 ]; then
    # --no-install-recommends: otherwise ParaView and ~280 packages (1.5 GB) come along
    $SUDO apt-get install -y --no-install-recommends liggghts liggghts-doc openmpi-bin
fi
command -v interFoam >/dev/null && command -v liggghts >/dev/null && command -v mpirun >/dev/null
echo "install_tools: done"
