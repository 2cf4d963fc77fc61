#!/usr/bin/env bash
# Make sure the simulators and synthesis tools are present; install the Debian packages when root.
#   ghdl, ghdl-mcode, ghdl-llvm  VHDL simulation: mcode for the short cocotb benches (it compiles in
#                    a second; without it Debian's ghdl wrapper falls back to LLVM, which compiles and
#                    links every bench, several seconds each), LLVM for long sweeps (~2.6x faster)
#   yosys            synthesis (synth_xilinx -family xcv) and its Xilinx cell models
#   verilator        post-synthesis netlist simulation; iverilog: the netlist regression test
#   nextpnr-ice40    iCE40 place and route + static timing (flann synth --device ice40-...)
#   fpga-icestorm    icepack (bitstream), icebox_vlog (post-route simulation); chip databases
set -euo pipefail
missing=()
command -v ghdl      >/dev/null 2>&1 || missing+=(ghdl)
command -v ghdl-mcode >/dev/null 2>&1 || missing+=(ghdl-mcode)
command -v ghdl-llvm >/dev/null 2>&1 || missing+=(ghdl-llvm)
command -v yosys     >/dev/null 2>&1 || missing+=(yosys)
command -v verilator >/dev/null 2>&1 || missing+=(verilator)
command -v iverilog  >/dev/null 2>&1 || missing+=(iverilog)
command -v nextpnr-ice40 >/dev/null 2>&1 || missing+=(nextpnr-ice40)
{ command -v icepack >/dev/null 2>&1 && command -v icebox_vlog >/dev/null 2>&1; } || missing+=(fpga-icestorm)
[ ${#missing[@]} -eq 0 ] && exit 0
if [ "$(id -u)" -ne 0 ]; then
    echo "error: ${missing[*]} not found; install them as root: apt-get update && apt-get install -y ${missing[*]}" >&2
    exit 2
fi
echo "installing Debian packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq "${missing[@]}" >/dev/null
