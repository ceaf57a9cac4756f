// SPDX-License-Identifier: MIT
// Running a program of ours as a user runs it, from a bench: the command line is
// built with shell quoting, stdout and stderr go to files that are read back.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace cpstep::tb {

struct Outcome {
  int rc = -1;  // the exit code; -1 when the program did not exit normally
  std::string out, err;
};

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Shell quoting for the paths and arguments of our tests (none holds a single
// quote). Built by append: GCC 12 warns falsely (-Wrestrict) on "literal" + std::string&&.
inline std::string quote(const std::string& s) {
  std::string q = "'";
  q.append(s).append("'");
  return q;
}

// Runs `program args...`; its stdout and stderr are kept in `dir`/`tag`.stdout
// and .stderr as well as returned.
inline Outcome run_program(const std::string& program, const std::vector<std::string>& args,
                           const std::filesystem::path& dir, const std::string& tag) {
  std::filesystem::create_directories(dir);
  std::string cmd = quote(program);
  for (const std::string& a : args) cmd.append(" ").append(quote(a));
  const std::filesystem::path out = dir / (tag + ".stdout"), err = dir / (tag + ".stderr");
  cmd.append(" >").append(quote(out.string())).append(" 2>").append(quote(err.string()));
  const int status = std::system(cmd.c_str());
  Outcome o;
  o.rc = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  o.out = slurp(out);
  o.err = slurp(err);
  return o;
}

}  // namespace cpstep::tb
