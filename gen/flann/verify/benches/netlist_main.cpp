// Verilator driver for the post-synthesis netlist of a one-input top (flann_top, or
// flann_family_top with CFG_ADDR_BITS defined): every code from argv[1] to argv[2], back to
// back, one line per sample ("code data sat latency") in argv[3], the same format as the VHDL
// sweep harness.  A family top first takes its weight image through the cfg port: argv[4], one
// hex word per line, address 0 first, exactly CFG_WORDS of them (a short or unreadable image
// would leave the memory's initial sensor in place and still match a twin of it).  The model
// is built with --prefix Vdut; IN_BITS / OUT_BITS (and CFG_ADDR_BITS, CFG_WORDS) come in as -D
// flags.
#include <cstdio>
#include <cstdlib>
#include "Vdut.h"
#include "verilated.h"

int main(int argc, char** argv) {
#ifdef CFG_ADDR_BITS
  const int args = 5;
#else
  const int args = 4;
#endif
  if (argc != args) {
    std::fprintf(stderr, "usage: %s CODE_LO CODE_HI OUT.txt%s\n", argv[0], args == 5 ? " IMAGE.txt" : "");
    return 2;
  }
  const long lo = std::atol(argv[1]), hi = std::atol(argv[2]);
  std::FILE* f = std::fopen(argv[3], "w");
  if (!f) return 2;
  Vdut* t = new Vdut;
  auto tick = [t]() { t->clk = 0; t->eval(); t->clk = 1; t->eval(); };
  t->clk = 0; t->rst = 1; t->in_valid = 0; t->in_data = 0;
#ifdef CFG_ADDR_BITS
  t->cfg_we = 0; t->cfg_addr = 0; t->cfg_data = 0;
#endif
  t->eval();
  tick(); tick();
  t->rst = 0;
#ifdef CFG_ADDR_BITS
  std::FILE* img = std::fopen(argv[4], "r");
  if (!img) {
    std::fprintf(stderr, "cannot open the weight image %s\n", argv[4]);
    return 2;
  }
  unsigned long word = 0, a = 0;
  for (; a < CFG_WORDS && std::fscanf(img, " %lx", &word) == 1; ++a) {
    t->cfg_we = 1; t->cfg_addr = a; t->cfg_data = static_cast<unsigned int>(word);
    tick();
  }
  const bool rest = std::fscanf(img, " %*s") != EOF;
  std::fclose(img);
  if (a != CFG_WORDS || rest || (a - 1) >> CFG_ADDR_BITS) {
    std::fprintf(stderr, "weight image %s: %lu hex words read, the memory takes %d\n", argv[4], a, CFG_WORDS);
    return 3;
  }
  t->cfg_we = 0;
  tick();
#endif
  const unsigned long long in_mask = (1ULL << IN_BITS) - 1;
  for (long c = lo; c <= hi; ++c) {
    t->in_data = static_cast<unsigned long long>(c) & in_mask;
    t->in_valid = 1;
    for (;;) {  // the edge that sees in_ready high takes the code
      const bool ready = t->in_ready;
      tick();
      if (ready) break;
    }
    t->in_valid = 0;
    long lat = 0;
    do { tick(); ++lat; } while (!t->out_valid && lat < 1000000);
    long long d = static_cast<long long>(t->out_data);
    if (d >> (OUT_BITS - 1)) d -= 1LL << OUT_BITS;
    std::fprintf(f, "%ld %lld %d %ld\n", c, d, static_cast<int>(t->out_sat), lat);
    if ((c - lo) % 256 == 255) std::fflush(f);
  }
  if (std::fclose(f) != 0) return 2;
  t->final();
  std::fflush(stderr);
  // the results are written: leave without the model's destructor (Verilator 5.006's teardown
  // of some netlists with block RAMs aborts in free(); the operating system frees the model)
  std::_Exit(0);
}
