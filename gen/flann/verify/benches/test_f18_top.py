"""cocotb: flann_f18_top against its twin FlannF18Top over a list of input codes (bit-exact),
through the one top bench (:class:`~flann.verify.benches.flann_bench.TopBench`).

The expected outputs come from the twin, computed by the runner and passed in the bench
configuration (flann.verify.benches.config; GHDL's VPI cannot read generics):
{"codes": [...], "out": [...], "sat": [...], "latency": N, "in_bits": B, "seed": S,
 "records": optional path where the HDL's outputs are written as JSON,
 "stage_codes": optional codes at which the internal stages are captured too}

Stage capture (monitors on the top's own signals, read through GHDL's VPI): every
converted term (term_f at term_valid), product (prod_f at prod_valid) and running sum
(sum_f at sum_valid), in order, for ``flann trace --hdl`` to compare with the twin.
"""

import json

import cocotb
from cocotb.triggers import ReadOnly, RisingEdge

from flann.verify.benches import config
from flann.verify.benches.flann_bench import TableTwin, TopBench


async def capture(valid, data, out: list):
    """Monitor one internal stage: the data of every valid pulse, in order."""
    while True:
        await RisingEdge(valid)
        await ReadOnly()
        out.append(data.value.to_unsigned())


@cocotb.test()
async def every_code(dut):
    cfg = config()
    bench = TopBench(dut, TableTwin(cfg["codes"], cfg["out"], cfg["sat"], cfg["latency"]), cfg, signed=False)
    dut._log.info(f"seed {cfg['seed']}, {len(cfg['codes'])} codes")
    await bench.start()
    order = list(cfg["codes"])
    bench.rng.shuffle(order)                # independent of the previous sample's state
    stage_codes, stages = set(cfg.get("stage_codes", [])), {}
    for code in order:
        monitors = []
        if code in stage_codes:
            st = stages[code] = {"terms": [], "products": [], "sums": []}
            monitors = [cocotb.start_soon(capture(dut.term_valid, dut.term_f, st["terms"])),
                        cocotb.start_soon(capture(dut.prod_valid, dut.prod_f, st["products"])),
                        cocotb.start_soon(capture(dut.sum_valid, dut.sum_f, st["sums"]))]
        await bench.run_codes([code])
        for m in monitors:
            m.cancel()
    sb = bench.sb
    latencies = sorted(set(sb.latencies))
    if cfg.get("records"):
        # the HDL's own outputs, for `flann trace --hdl` and the runner's summary
        with open(cfg["records"], "w") as fh:
            json.dump({"codes": [r[0] for r in sb.records], "out": [r[1] for r in sb.records],
                       "sat": [r[2] for r in sb.records], "latency": latencies,
                       "stages": {str(c): v for c, v in stages.items()}}, fh)
    dut._log.info(f"{sb.checked - sb.mismatches} of {len(order)} codes bit-exact; latency {latencies}")
    assert sb.ok and sb.checked == len(order), f"{sb.mismatches} mismatches vs the twin"
    assert latencies == [cfg["latency"]], f"latency {latencies}, spec says {cfg['latency']}"
