#!/usr/bin/env bash
# Install headless Chromium and its WebDriver (Debian 12 packages `chromium`, `chromium-driver`)
# for the nightly report's real-browser test (tests/test_report_browser.py).
# Idempotent: does nothing when both are installed. Needs root (or sudo). Used by CI (.ci/run).
set -euo pipefail

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    SUDO="sudo"
fi

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }

if installed chromium && installed chromium-driver; then
    echo "install_browser: chromium, chromium-driver already installed"
    exit 0
fi

export DEBIAN_FRONTEND=noninteractive
# apt-get update only if the package lists are missing or older than a day
if [ -z "$(find /var/lib/apt/lists -maxdepth 1 -name '*_Packages*' -mmin -1440 2>/dev/null | head -1)" ]; then
    $SUDO apt-get update
fi
# --no-install-recommends: the browser and its driver only (no desktop integration, fonts beyond the needed)
$SUDO apt-get install -y --no-install-recommends chromium chromium-driver
command -v chromium >/dev/null && command -v chromedriver >/dev/null
echo "install_browser: done ($(chromium --version 2>/dev/null || echo chromium))"
