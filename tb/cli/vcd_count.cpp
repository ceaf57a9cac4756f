// SPDX-License-Identifier: MIT
// vcd_count FILE — summarises a VCD for the CLI tests, independently of the
// writer in host/sim: the timescale, every variable in declaration order, and per
// variable its width, rising and falling edges of bit 0 and final value, plus the
// gcd of all timestamps (so a test can check the clock period divides them).
//
// Output:
//   timescale <unit>
//   signals <name> <name> ...
//   <name> width=<w> rises=<n> falls=<n> final=<0|1|x>
//   time_gcd=<g> end_time=<t>
// Exit 1 with a message if the file is not a VCD this tool can read.
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct Var {
  std::string name;
  unsigned width = 0;
  char value = 'x';  // bit 0
  uint64_t rises = 0, falls = 0;
};

[[noreturn]] void die(const std::string& msg) {
  std::cerr << "vcd_count: " << msg << "\n";
  std::exit(1);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) die("usage: vcd_count FILE");
  std::ifstream in(argv[1]);
  if (!in) die(std::string("cannot read ") + argv[1]);
  std::stringstream all;
  all << in.rdbuf();

  // The whole file as whitespace-separated tokens: VCD is token-based.
  std::vector<std::string> tok;
  for (std::string t; all >> t;) tok.push_back(t);

  std::string timescale;
  std::vector<Var> vars;
  std::map<std::string, size_t> by_code;
  uint64_t time = 0, time_gcd = 0;
  bool defs_done = false;
  auto change = [&](const std::string& code, char bit) {
    const auto it = by_code.find(code);
    if (it == by_code.end()) die("value change for undeclared code " + code);
    Var& v = vars[it->second];
    if (v.value == '0' && bit == '1') ++v.rises;
    if (v.value == '1' && bit == '0') ++v.falls;
    v.value = bit;
  };
  for (size_t i = 0; i < tok.size(); ++i) {
    const std::string& t = tok[i];
    if (t == "$timescale") {
      for (++i; i < tok.size() && tok[i] != "$end"; ++i) timescale += tok[i];
    } else if (t == "$var") {
      // $var <type> <width> <code> <name> [range] $end
      if (i + 4 >= tok.size()) die("truncated $var");
      Var v;
      v.width = unsigned(std::stoul(tok[i + 2]));
      const std::string code = tok[i + 3];
      v.name = tok[i + 4];
      if (by_code.count(code)) die("code " + code + " declared twice");
      by_code[code] = vars.size();
      vars.push_back(v);
      for (i += 5; i < tok.size() && tok[i] != "$end"; ++i) {}
    } else if (t == "$enddefinitions") {
      defs_done = true;
    } else if (t == "$scope" || t == "$upscope" || t == "$comment" || t == "$date" || t == "$version") {
      for (++i; i < tok.size() && tok[i] != "$end"; ++i) {}
    } else if (t == "$dumpvars" || t == "$end" || t == "$dumpall" || t == "$dumpon" || t == "$dumpoff") {
      // value changes inside these blocks are read like any others
    } else if (!defs_done) {
      die("unexpected token before $enddefinitions: " + t);
    } else if (t[0] == '#') {
      const uint64_t next = std::stoull(t.substr(1));
      if (next < time) die("time goes backwards at " + t);
      time = next;
      time_gcd = std::gcd(time_gcd, time);
    } else if (t[0] == 'b' || t[0] == 'B') {
      if (i + 1 >= tok.size()) die("truncated vector change");
      change(tok[i + 1], t.back() == '1' ? '1' : t.back() == '0' ? '0' : 'x');
      ++i;
    } else if (t[0] == '0' || t[0] == '1' || t[0] == 'x' || t[0] == 'X' || t[0] == 'z' || t[0] == 'Z') {
      change(t.substr(1), t[0] == '1' ? '1' : t[0] == '0' ? '0' : 'x');
    } else {
      die("unexpected token: " + t);
    }
  }
  if (!defs_done) die("no $enddefinitions");
  std::cout << "timescale " << timescale << "\nsignals";
  for (const Var& v : vars) std::cout << ' ' << v.name;
  std::cout << '\n';
  for (const Var& v : vars)
    std::cout << v.name << " width=" << v.width << " rises=" << v.rises << " falls=" << v.falls
              << " final=" << v.value << '\n';
  std::cout << "time_gcd=" << time_gcd << " end_time=" << time << '\n';
  return 0;
}
