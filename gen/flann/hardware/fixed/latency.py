"""Latencies of the shared blocks, each written once: the twins state them (``latency``) and
the specs sum them into a top level's ``latency_cycles`` (checked by the top-level benches).

Clock edges unless said otherwise; an *advance* is one pipeline step the sequencer issues every
``adv_period`` cycles.
"""

# flann_norm: accepting edge to out_valid = one edge per code bit, one to add the offsets
NORM_EXTRA_EDGES = 1
# flann_seq: norm's out_valid to the run state, and to the first advance
SEQ_START_EDGES = 2
# flann_expansion: advances from theta to the first term
EXPANSION_ADVANCES = 3
# flann_multiplier: advances from term to product (operands, then the rounded product)
MULTIPLIER_ADVANCES = 2
# flann_adder: in_finish to out_valid (the rounded, saturated sum registered)
ADDER_EDGES = 1


def norm_latency(input_bits: int) -> int:
    return int(input_bits) + NORM_EXTRA_EDGES


__all__ = ["NORM_EXTRA_EDGES", "SEQ_START_EDGES", "EXPANSION_ADVANCES", "MULTIPLIER_ADVANCES", "ADDER_EDGES",
           "norm_latency"]
