// Verilator driver for the post-synthesis netlist of a flann top: every code from argv[1] to
// argv[2], back to back, one line per sample ("code data sat latency") in argv[3], the same
// format as the VHDL sweep harness.  A top with a temperature input (TEMP_BITS defined) runs the
// codes at each temperature code of the next argument (one decimal code per line) and adds the
// temperature code as a fifth column.  A family top (CFG_ADDR_BITS defined) first takes its
// weight image through the cfg port: the last argument, one hex word per line, address 0 first,
// exactly CFG_WORDS of them (a short or unreadable image would leave the memory's initial sensor
// in place and still match a twin of it).  The model is built with --prefix Vdut; IN_BITS /
// OUT_BITS (TEMP_BITS, CFG_ADDR_BITS, CFG_WORDS) come in as -D flags.
#include <vector>
#include <cstdio>
#include <cstdlib>
#include "Vdut.h"
#include "verilated.h"

int main(int argc, char** argv) {
  int args = 4;
#ifdef TEMP_BITS
  const int temps_arg = args++;
#endif
#ifdef CFG_ADDR_BITS
  const int image_arg = args++;
#endif
  if (argc != args) {
    std::fprintf(stderr, "usage: %s CODE_LO CODE_HI OUT.txt [TEMPS.txt] [IMAGE.txt] (%d arguments)\n", argv[0],
                 args - 1);
    return 2;
  }
  const long lo = std::atol(argv[1]), hi = std::atol(argv[2]);
  std::vector<long> temps(1, 0);
#ifdef TEMP_BITS
  {
    std::FILE* tf = std::fopen(argv[temps_arg], "r");
    if (!tf) {
      std::fprintf(stderr, "cannot open the temperature codes %s\n", argv[temps_arg]);
      return 2;
    }
    temps.clear();
    long code = 0;
    while (std::fscanf(tf, " %ld", &code) == 1) temps.push_back(code);
    std::fclose(tf);
    if (temps.empty()) {
      std::fprintf(stderr, "no temperature codes in %s\n", argv[temps_arg]);
      return 3;
    }
  }
#endif
  std::FILE* f = std::fopen(argv[3], "w");
  if (!f) return 2;
  Vdut* t = new Vdut;
  auto tick = [t]() { t->clk = 0; t->eval(); t->clk = 1; t->eval(); };
  t->clk = 0; t->rst = 1; t->in_valid = 0; t->in_data = 0;
#ifdef TEMP_BITS
  t->in_temp = 0;
#endif
#ifdef CFG_ADDR_BITS
  t->cfg_we = 0; t->cfg_addr = 0; t->cfg_data = 0;
#endif
  t->eval();
  tick(); tick();
  t->rst = 0;
#ifdef CFG_ADDR_BITS
  std::FILE* img = std::fopen(argv[image_arg], "r");
  if (!img) {
    std::fprintf(stderr, "cannot open the weight image %s\n", argv[image_arg]);
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
    std::fprintf(stderr, "weight image %s: %lu hex words read, the memory takes %d\n", argv[image_arg], a,
                 CFG_WORDS);
    return 3;
  }
  t->cfg_we = 0;
  tick();
#endif
  const unsigned long long in_mask = (1ULL << IN_BITS) - 1;
  long done = 0;
  for (const long temp : temps) {
#ifdef TEMP_BITS
    t->in_temp = static_cast<unsigned long long>(temp) & ((1ULL << TEMP_BITS) - 1);
#endif
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
#ifdef TEMP_BITS
      std::fprintf(f, "%ld %lld %d %ld %ld\n", c, d, static_cast<int>(t->out_sat), lat, temp);
#else
      std::fprintf(f, "%ld %lld %d %ld\n", c, d, static_cast<int>(t->out_sat), lat);
#endif
      if (++done % 256 == 0) std::fflush(f);
    }
  }
  if (std::fclose(f) != 0) return 2;
  t->final();
  std::fflush(stderr);
  // the results are written: leave without the model's destructor (Verilator 5.006's teardown
  // of some netlists with block RAMs aborts in free(); the operating system frees the model)
  std::_Exit(0);
}
