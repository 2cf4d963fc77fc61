// Virtex / Spartan-II block RAMs (4096 bits), single and dual port, for simulating Yosys's synth_xilinx
// -family xcv netlists: Yosys's cells_sim.v has no RAMB4 models.  Behaviour as in the Xilinx
// libraries guide: read and write on the rising CLK when EN, write-first, RST clears DO;
// INIT_00..INIT_0F hold the contents, address 0 in the low bits of INIT_00.

module RAMB4_S1 (DO, ADDR, DI, EN, CLK, WE, RST);
  parameter INIT_00 = 256'h0; parameter INIT_01 = 256'h0; parameter INIT_02 = 256'h0; parameter INIT_03 = 256'h0;
  parameter INIT_04 = 256'h0; parameter INIT_05 = 256'h0; parameter INIT_06 = 256'h0; parameter INIT_07 = 256'h0;
  parameter INIT_08 = 256'h0; parameter INIT_09 = 256'h0; parameter INIT_0A = 256'h0; parameter INIT_0B = 256'h0;
  parameter INIT_0C = 256'h0; parameter INIT_0D = 256'h0; parameter INIT_0E = 256'h0; parameter INIT_0F = 256'h0;
  output reg [0:0] DO;
  input [11:0] ADDR;
  input [0:0] DI;
  input EN, CLK, WE, RST;
  reg [4095:0] mem;
  initial begin
    mem = {INIT_0F, INIT_0E, INIT_0D, INIT_0C, INIT_0B, INIT_0A, INIT_09, INIT_08,
           INIT_07, INIT_06, INIT_05, INIT_04, INIT_03, INIT_02, INIT_01, INIT_00};
    DO = 0;
  end
  always @(posedge CLK)
    if (EN) begin
      if (WE) mem[ADDR * 1 +: 1] <= DI;
      if (RST) DO <= 0;
      else if (WE) DO <= DI;
      else DO <= mem[ADDR * 1 +: 1];
    end
endmodule

module RAMB4_S2 (DO, ADDR, DI, EN, CLK, WE, RST);
  parameter INIT_00 = 256'h0; parameter INIT_01 = 256'h0; parameter INIT_02 = 256'h0; parameter INIT_03 = 256'h0;
  parameter INIT_04 = 256'h0; parameter INIT_05 = 256'h0; parameter INIT_06 = 256'h0; parameter INIT_07 = 256'h0;
  parameter INIT_08 = 256'h0; parameter INIT_09 = 256'h0; parameter INIT_0A = 256'h0; parameter INIT_0B = 256'h0;
  parameter INIT_0C = 256'h0; parameter INIT_0D = 256'h0; parameter INIT_0E = 256'h0; parameter INIT_0F = 256'h0;
  output reg [1:0] DO;
  input [10:0] ADDR;
  input [1:0] DI;
  input EN, CLK, WE, RST;
  reg [4095:0] mem;
  initial begin
    mem = {INIT_0F, INIT_0E, INIT_0D, INIT_0C, INIT_0B, INIT_0A, INIT_09, INIT_08,
           INIT_07, INIT_06, INIT_05, INIT_04, INIT_03, INIT_02, INIT_01, INIT_00};
    DO = 0;
  end
  always @(posedge CLK)
    if (EN) begin
      if (WE) mem[ADDR * 2 +: 2] <= DI;
      if (RST) DO <= 0;
      else if (WE) DO <= DI;
      else DO <= mem[ADDR * 2 +: 2];
    end
endmodule

module RAMB4_S4 (DO, ADDR, DI, EN, CLK, WE, RST);
  parameter INIT_00 = 256'h0; parameter INIT_01 = 256'h0; parameter INIT_02 = 256'h0; parameter INIT_03 = 256'h0;
  parameter INIT_04 = 256'h0; parameter INIT_05 = 256'h0; parameter INIT_06 = 256'h0; parameter INIT_07 = 256'h0;
  parameter INIT_08 = 256'h0; parameter INIT_09 = 256'h0; parameter INIT_0A = 256'h0; parameter INIT_0B = 256'h0;
  parameter INIT_0C = 256'h0; parameter INIT_0D = 256'h0; parameter INIT_0E = 256'h0; parameter INIT_0F = 256'h0;
  output reg [3:0] DO;
  input [9:0] ADDR;
  input [3:0] DI;
  input EN, CLK, WE, RST;
  reg [4095:0] mem;
  initial begin
    mem = {INIT_0F, INIT_0E, INIT_0D, INIT_0C, INIT_0B, INIT_0A, INIT_09, INIT_08,
           INIT_07, INIT_06, INIT_05, INIT_04, INIT_03, INIT_02, INIT_01, INIT_00};
    DO = 0;
  end
  always @(posedge CLK)
    if (EN) begin
      if (WE) mem[ADDR * 4 +: 4] <= DI;
      if (RST) DO <= 0;
      else if (WE) DO <= DI;
      else DO <= mem[ADDR * 4 +: 4];
    end
endmodule

module RAMB4_S8 (DO, ADDR, DI, EN, CLK, WE, RST);
  parameter INIT_00 = 256'h0; parameter INIT_01 = 256'h0; parameter INIT_02 = 256'h0; parameter INIT_03 = 256'h0;
  parameter INIT_04 = 256'h0; parameter INIT_05 = 256'h0; parameter INIT_06 = 256'h0; parameter INIT_07 = 256'h0;
  parameter INIT_08 = 256'h0; parameter INIT_09 = 256'h0; parameter INIT_0A = 256'h0; parameter INIT_0B = 256'h0;
  parameter INIT_0C = 256'h0; parameter INIT_0D = 256'h0; parameter INIT_0E = 256'h0; parameter INIT_0F = 256'h0;
  output reg [7:0] DO;
  input [8:0] ADDR;
  input [7:0] DI;
  input EN, CLK, WE, RST;
  reg [4095:0] mem;
  initial begin
    mem = {INIT_0F, INIT_0E, INIT_0D, INIT_0C, INIT_0B, INIT_0A, INIT_09, INIT_08,
           INIT_07, INIT_06, INIT_05, INIT_04, INIT_03, INIT_02, INIT_01, INIT_00};
    DO = 0;
  end
  always @(posedge CLK)
    if (EN) begin
      if (WE) mem[ADDR * 8 +: 8] <= DI;
      if (RST) DO <= 0;
      else if (WE) DO <= DI;
      else DO <= mem[ADDR * 8 +: 8];
    end
endmodule

module RAMB4_S16 (DO, ADDR, DI, EN, CLK, WE, RST);
  parameter INIT_00 = 256'h0; parameter INIT_01 = 256'h0; parameter INIT_02 = 256'h0; parameter INIT_03 = 256'h0;
  parameter INIT_04 = 256'h0; parameter INIT_05 = 256'h0; parameter INIT_06 = 256'h0; parameter INIT_07 = 256'h0;
  parameter INIT_08 = 256'h0; parameter INIT_09 = 256'h0; parameter INIT_0A = 256'h0; parameter INIT_0B = 256'h0;
  parameter INIT_0C = 256'h0; parameter INIT_0D = 256'h0; parameter INIT_0E = 256'h0; parameter INIT_0F = 256'h0;
  output reg [15:0] DO;
  input [7:0] ADDR;
  input [15:0] DI;
  input EN, CLK, WE, RST;
  reg [4095:0] mem;
  initial begin
    mem = {INIT_0F, INIT_0E, INIT_0D, INIT_0C, INIT_0B, INIT_0A, INIT_09, INIT_08,
           INIT_07, INIT_06, INIT_05, INIT_04, INIT_03, INIT_02, INIT_01, INIT_00};
    DO = 0;
  end
  always @(posedge CLK)
    if (EN) begin
      if (WE) mem[ADDR * 16 +: 16] <= DI;
      if (RST) DO <= 0;
      else if (WE) DO <= DI;
      else DO <= mem[ADDR * 16 +: 16];
    end
endmodule

// Dual-port block RAMs with both ports of the same width (a ROM read at two addresses maps to
// one of these): each port as the single-port model, one shared memory.  Both ports are
// modelled on CLKA (the generator's designs have one clock; two processes writing one memory
// made Verilator's model abort at exit).

module RAMB4_S1_S1 (DOA, DOB, ADDRA, ADDRB, DIA, DIB, ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB);
  parameter INIT_00 = 256'h0; parameter INIT_01 = 256'h0; parameter INIT_02 = 256'h0; parameter INIT_03 = 256'h0;
  parameter INIT_04 = 256'h0; parameter INIT_05 = 256'h0; parameter INIT_06 = 256'h0; parameter INIT_07 = 256'h0;
  parameter INIT_08 = 256'h0; parameter INIT_09 = 256'h0; parameter INIT_0A = 256'h0; parameter INIT_0B = 256'h0;
  parameter INIT_0C = 256'h0; parameter INIT_0D = 256'h0; parameter INIT_0E = 256'h0; parameter INIT_0F = 256'h0;
  output reg [0:0] DOA, DOB;
  input [11:0] ADDRA, ADDRB;
  input [0:0] DIA, DIB;
  input ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB;
  reg [4095:0] mem;
  initial begin
    mem = {INIT_0F, INIT_0E, INIT_0D, INIT_0C, INIT_0B, INIT_0A, INIT_09, INIT_08,
           INIT_07, INIT_06, INIT_05, INIT_04, INIT_03, INIT_02, INIT_01, INIT_00};
    DOA = 0;
    DOB = 0;
  end
  always @(posedge CLKA) begin
    if (ENA) begin
      if (RSTA) DOA <= 0;
      else if (WEA) DOA <= DIA;
      else DOA <= mem[ADDRA * 1 +: 1];
    end
    if (ENB) begin
      if (RSTB) DOB <= 0;
      else if (WEB) DOB <= DIB;
      else DOB <= mem[ADDRB * 1 +: 1];
    end
    if (ENA && WEA) mem[ADDRA * 1 +: 1] <= DIA;
    if (ENB && WEB) mem[ADDRB * 1 +: 1] <= DIB;
  end
endmodule

module RAMB4_S2_S2 (DOA, DOB, ADDRA, ADDRB, DIA, DIB, ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB);
  parameter INIT_00 = 256'h0; parameter INIT_01 = 256'h0; parameter INIT_02 = 256'h0; parameter INIT_03 = 256'h0;
  parameter INIT_04 = 256'h0; parameter INIT_05 = 256'h0; parameter INIT_06 = 256'h0; parameter INIT_07 = 256'h0;
  parameter INIT_08 = 256'h0; parameter INIT_09 = 256'h0; parameter INIT_0A = 256'h0; parameter INIT_0B = 256'h0;
  parameter INIT_0C = 256'h0; parameter INIT_0D = 256'h0; parameter INIT_0E = 256'h0; parameter INIT_0F = 256'h0;
  output reg [1:0] DOA, DOB;
  input [10:0] ADDRA, ADDRB;
  input [1:0] DIA, DIB;
  input ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB;
  reg [4095:0] mem;
  initial begin
    mem = {INIT_0F, INIT_0E, INIT_0D, INIT_0C, INIT_0B, INIT_0A, INIT_09, INIT_08,
           INIT_07, INIT_06, INIT_05, INIT_04, INIT_03, INIT_02, INIT_01, INIT_00};
    DOA = 0;
    DOB = 0;
  end
  always @(posedge CLKA) begin
    if (ENA) begin
      if (RSTA) DOA <= 0;
      else if (WEA) DOA <= DIA;
      else DOA <= mem[ADDRA * 2 +: 2];
    end
    if (ENB) begin
      if (RSTB) DOB <= 0;
      else if (WEB) DOB <= DIB;
      else DOB <= mem[ADDRB * 2 +: 2];
    end
    if (ENA && WEA) mem[ADDRA * 2 +: 2] <= DIA;
    if (ENB && WEB) mem[ADDRB * 2 +: 2] <= DIB;
  end
endmodule

module RAMB4_S4_S4 (DOA, DOB, ADDRA, ADDRB, DIA, DIB, ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB);
  parameter INIT_00 = 256'h0; parameter INIT_01 = 256'h0; parameter INIT_02 = 256'h0; parameter INIT_03 = 256'h0;
  parameter INIT_04 = 256'h0; parameter INIT_05 = 256'h0; parameter INIT_06 = 256'h0; parameter INIT_07 = 256'h0;
  parameter INIT_08 = 256'h0; parameter INIT_09 = 256'h0; parameter INIT_0A = 256'h0; parameter INIT_0B = 256'h0;
  parameter INIT_0C = 256'h0; parameter INIT_0D = 256'h0; parameter INIT_0E = 256'h0; parameter INIT_0F = 256'h0;
  output reg [3:0] DOA, DOB;
  input [9:0] ADDRA, ADDRB;
  input [3:0] DIA, DIB;
  input ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB;
  reg [4095:0] mem;
  initial begin
    mem = {INIT_0F, INIT_0E, INIT_0D, INIT_0C, INIT_0B, INIT_0A, INIT_09, INIT_08,
           INIT_07, INIT_06, INIT_05, INIT_04, INIT_03, INIT_02, INIT_01, INIT_00};
    DOA = 0;
    DOB = 0;
  end
  always @(posedge CLKA) begin
    if (ENA) begin
      if (RSTA) DOA <= 0;
      else if (WEA) DOA <= DIA;
      else DOA <= mem[ADDRA * 4 +: 4];
    end
    if (ENB) begin
      if (RSTB) DOB <= 0;
      else if (WEB) DOB <= DIB;
      else DOB <= mem[ADDRB * 4 +: 4];
    end
    if (ENA && WEA) mem[ADDRA * 4 +: 4] <= DIA;
    if (ENB && WEB) mem[ADDRB * 4 +: 4] <= DIB;
  end
endmodule

module RAMB4_S8_S8 (DOA, DOB, ADDRA, ADDRB, DIA, DIB, ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB);
  parameter INIT_00 = 256'h0; parameter INIT_01 = 256'h0; parameter INIT_02 = 256'h0; parameter INIT_03 = 256'h0;
  parameter INIT_04 = 256'h0; parameter INIT_05 = 256'h0; parameter INIT_06 = 256'h0; parameter INIT_07 = 256'h0;
  parameter INIT_08 = 256'h0; parameter INIT_09 = 256'h0; parameter INIT_0A = 256'h0; parameter INIT_0B = 256'h0;
  parameter INIT_0C = 256'h0; parameter INIT_0D = 256'h0; parameter INIT_0E = 256'h0; parameter INIT_0F = 256'h0;
  output reg [7:0] DOA, DOB;
  input [8:0] ADDRA, ADDRB;
  input [7:0] DIA, DIB;
  input ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB;
  reg [4095:0] mem;
  initial begin
    mem = {INIT_0F, INIT_0E, INIT_0D, INIT_0C, INIT_0B, INIT_0A, INIT_09, INIT_08,
           INIT_07, INIT_06, INIT_05, INIT_04, INIT_03, INIT_02, INIT_01, INIT_00};
    DOA = 0;
    DOB = 0;
  end
  always @(posedge CLKA) begin
    if (ENA) begin
      if (RSTA) DOA <= 0;
      else if (WEA) DOA <= DIA;
      else DOA <= mem[ADDRA * 8 +: 8];
    end
    if (ENB) begin
      if (RSTB) DOB <= 0;
      else if (WEB) DOB <= DIB;
      else DOB <= mem[ADDRB * 8 +: 8];
    end
    if (ENA && WEA) mem[ADDRA * 8 +: 8] <= DIA;
    if (ENB && WEB) mem[ADDRB * 8 +: 8] <= DIB;
  end
endmodule

module RAMB4_S16_S16 (DOA, DOB, ADDRA, ADDRB, DIA, DIB, ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB);
  parameter INIT_00 = 256'h0; parameter INIT_01 = 256'h0; parameter INIT_02 = 256'h0; parameter INIT_03 = 256'h0;
  parameter INIT_04 = 256'h0; parameter INIT_05 = 256'h0; parameter INIT_06 = 256'h0; parameter INIT_07 = 256'h0;
  parameter INIT_08 = 256'h0; parameter INIT_09 = 256'h0; parameter INIT_0A = 256'h0; parameter INIT_0B = 256'h0;
  parameter INIT_0C = 256'h0; parameter INIT_0D = 256'h0; parameter INIT_0E = 256'h0; parameter INIT_0F = 256'h0;
  output reg [15:0] DOA, DOB;
  input [7:0] ADDRA, ADDRB;
  input [15:0] DIA, DIB;
  input ENA, ENB, CLKA, CLKB, WEA, WEB, RSTA, RSTB;
  reg [4095:0] mem;
  initial begin
    mem = {INIT_0F, INIT_0E, INIT_0D, INIT_0C, INIT_0B, INIT_0A, INIT_09, INIT_08,
           INIT_07, INIT_06, INIT_05, INIT_04, INIT_03, INIT_02, INIT_01, INIT_00};
    DOA = 0;
    DOB = 0;
  end
  always @(posedge CLKA) begin
    if (ENA) begin
      if (RSTA) DOA <= 0;
      else if (WEA) DOA <= DIA;
      else DOA <= mem[ADDRA * 16 +: 16];
    end
    if (ENB) begin
      if (RSTB) DOB <= 0;
      else if (WEB) DOB <= DIB;
      else DOB <= mem[ADDRB * 16 +: 16];
    end
    if (ENA && WEA) mem[ADDRA * 16 +: 16] <= DIA;
    if (ENB && WEB) mem[ADDRB * 16 +: 16] <= DIB;
  end
endmodule
