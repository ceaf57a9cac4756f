// SPDX-License-Identifier: MIT
// A fuzz target without libFuzzer: runs LLVMFuzzerTestOneInput on each file named
// on the command line, or on every file of each directory named (sorted), and
// prints how many it ran. The normal build runs the seed corpora through it (ctest
// label unit); a crash or a failed invariant aborts, and an input that takes the
// process's peak memory past libFuzzer's limit (-rss_limit_mb, 2048 MB, which
// scripts/fuzz and the smoke tests use) fails the run, naming it: without ASan an
// out-of-memory finding would otherwise replay as a pass.
#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "fuzz_util.h"

namespace fs = std::filesystem;

constexpr long kRssLimitMb = 2048;

static long peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024;  // (Linux: kilobytes)
}

static bool run_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) {
    std::fprintf(stderr, "replay: cannot read %s\n", p.c_str());
    return false;
  }
  const std::vector<char> bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const long before = peak_rss_mb();
  LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  const long after = peak_rss_mb();
  if (before <= kRssLimitMb && after > kRssLimitMb) {  // (the peak only grows: the input that passes it)
    std::fprintf(stderr, "replay: %s: peak memory %ld MB, past libFuzzer's limit of %ld MB\n", p.c_str(), after,
                 kRssLimitMb);
    return false;
  }
  return true;
}

int main(int argc, char** argv) {
  size_t runs = 0;
  bool ok = true;
  for (int a = 1; a < argc; ++a) {
    const fs::path arg = argv[a];
    std::vector<fs::path> files;
    if (fs::is_directory(arg)) {
      for (const auto& e : fs::recursive_directory_iterator(arg))
        if (e.is_regular_file()) files.push_back(e.path());
      std::sort(files.begin(), files.end());
    } else {
      files.push_back(arg);
    }
    for (const auto& f : files) {
      ok = run_file(f) && ok;
      ++runs;
    }
  }
  std::printf("replay: %zu input(s)\n", runs);
  return ok && runs > 0 ? 0 : 1;
}
