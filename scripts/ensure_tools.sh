#!/usr/bin/env bash
# Make sure GHDL (mcode) and Yosys are present; install the Debian packages when root.
set -euo pipefail
missing=()
command -v ghdl  >/dev/null 2>&1 || missing+=(ghdl)
command -v yosys >/dev/null 2>&1 || missing+=(yosys)
[ ${#missing[@]} -eq 0 ] && exit 0
if [ "$(id -u)" -ne 0 ]; then
    echo "error: ${missing[*]} not found; install them as root: apt-get update && apt-get install -y ghdl yosys" >&2
    exit 2
fi
echo "installing Debian packages: ghdl yosys"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq ghdl yosys >/dev/null
