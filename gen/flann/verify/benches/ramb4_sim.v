// Virtex / Spartan-II block RAMs (4096 bits), single and dual port, for simulating Yosys's synth_xilinx
// -family xcv netlists: Yosys's cells_sim.v has no RAMB4 models.  Behaviour as in the Xilinx
// libraries guide: read and write on the rising CLK when EN, write-first, RST clears DO;
// INIT_00..INIT_0F hold the contents, address 0 in the low bits of INIT_00.
// Every width is one macro call: the contents (RAMB4_MEM) are written once, each port kind
// (RAMB4_SINGLE, RAMB4_DUAL) once, with the data width W and the address width A as arguments.
// The contents are W-bit words filled by a loop, not one 4096-bit register set from one constant,
// which the simulator (5.006) sets in 256-bit chunks whose top chunk's zero fill (VL_CONSTHI_W_*)
// writes past the register's end by the chunk's offset: that corrupted the heap.

`define RAMB4_MEM(W) \
  parameter INIT_00 = 256'h0; parameter INIT_01 = 256'h0; parameter INIT_02 = 256'h0; parameter INIT_03 = 256'h0; \
  parameter INIT_04 = 256'h0; parameter INIT_05 = 256'h0; parameter INIT_06 = 256'h0; parameter INIT_07 = 256'h0; \
  parameter INIT_08 = 256'h0; parameter INIT_09 = 256'h0; parameter INIT_0A = 256'h0; parameter INIT_0B = 256'h0; \
  parameter INIT_0C = 256'h0; parameter INIT_0D = 256'h0; parameter INIT_0E = 256'h0; parameter INIT_0F = 256'h0; \
  localparam [4095:0] INIT = {INIT_0F, INIT_0E, INIT_0D, INIT_0C, INIT_0B, INIT_0A, INIT_09, INIT_08, \
                              INIT_07, INIT_06, INIT_05, INIT_04, INIT_03, INIT_02, INIT_01, INIT_00}; \
  reg [W-1:0] mem [0:4096/W-1]; \
  integer i; \
  initial for (i = 0; i < 4096 / W; i = i + 1) mem[i] = INIT[i * W +: W];

`define RAMB4_SINGLE(NAME, W, A) \
module NAME (DO, ADDR, DI, EN, CLK, WE, RST); \
  `RAMB4_MEM(W) \
  output reg [W-1:0] DO; \
  input [A-1:0] ADDR; \
  input [W-1:0] DI; \
  input EN, CLK, WE, RST; \
  initial DO = 0; \
  always @(posedge CLK) \
    if (EN) begin \
      if (WE) mem[ADDR] <= DI; \
      if (RST) DO <= 0; \
      else if (WE) DO <= DI; \
      else DO <= mem[ADDR]; \
    end \
endmodule

// Dual-port block RAMs with both ports of the same width (a ROM read at two addresses maps to
// one of these): each port as the single-port model, one shared memory.  Both ports are
// modelled on CLKA (the generator's designs have one clock; two processes writing one memory
// made Verilator's model abort at exit).
`define RAMB4_DUAL(NAME, W, A) \
module NAME (DOA, DOB, ADDRA, ADDRB, DIA, DIB, ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB); \
  `RAMB4_MEM(W) \
  output reg [W-1:0] DOA, DOB; \
  input [A-1:0] ADDRA, ADDRB; \
  input [W-1:0] DIA, DIB; \
  input ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB; \
  initial begin \
    DOA = 0; \
    DOB = 0; \
  end \
  always @(posedge CLKA) begin \
    if (ENA) begin \
      if (RSTA) DOA <= 0; \
      else if (WEA) DOA <= DIA; \
      else DOA <= mem[ADDRA]; \
    end \
    if (ENB) begin \
      if (RSTB) DOB <= 0; \
      else if (WEB) DOB <= DIB; \
      else DOB <= mem[ADDRB]; \
    end \
    if (ENA && WEA) mem[ADDRA] <= DIA; \
    if (ENB && WEB) mem[ADDRB] <= DIB; \
  end \
endmodule

`RAMB4_SINGLE(RAMB4_S1, 1, 12)
`RAMB4_SINGLE(RAMB4_S2, 2, 11)
`RAMB4_SINGLE(RAMB4_S4, 4, 10)
`RAMB4_SINGLE(RAMB4_S8, 8, 9)
`RAMB4_SINGLE(RAMB4_S16, 16, 8)

`RAMB4_DUAL(RAMB4_S1_S1, 1, 12)
`RAMB4_DUAL(RAMB4_S2_S2, 2, 11)
`RAMB4_DUAL(RAMB4_S4_S4, 4, 10)
`RAMB4_DUAL(RAMB4_S8_S8, 8, 9)
`RAMB4_DUAL(RAMB4_S16_S16, 16, 8)

`undef RAMB4_SINGLE
`undef RAMB4_DUAL
`undef RAMB4_MEM
