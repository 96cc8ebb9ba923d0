// Replays every input the fuzzer ever found (tests/fuzz/regressions/<dialect>/) and the dialect's whole
// conformance corpus through its fuzz entry point in the normal (sanitized) test build: a fixed crash stays
// fixed. The dialect is CELL_FUZZ_DIALECT (one CTest test per dialect, <dialect>_fuzz_regressions).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "cell/testing/process.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

namespace fs = std::filesystem;

std::vector<fs::path> Inputs(const fs::path& dir, const std::string& ext) {
  std::vector<fs::path> out;
  if (!fs::is_directory(dir)) return out;
  for (auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file() || e.path().filename() == "README.md") continue;
    if (!ext.empty() && e.path().extension() != ext) continue;
    out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

void Replay(const fs::path& p) {
  std::string text = cell::testing::ReadFile(p.string());
  SCOPED_TRACE(p.string());
  EXPECT_EQ(LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(text.data()), text.size()), 0);
}

std::string Dialect() {
  const char* d = std::getenv("CELL_FUZZ_DIALECT");
  return d ? d : "ktapl";
}

TEST(FuzzRegressions, EveryFoundInputRunsCleanly) {
  for (auto& p : Inputs(fs::path(cell::testing::SourceDir()) / "tests/fuzz/regressions" / Dialect(), ""))
    Replay(p);
}

TEST(FuzzRegressions, ConformanceCorpusThroughTheFuzzEntryPoint) {
  auto corpus =
      Inputs(fs::path(cell::testing::SourceDir()) / "tests/conformance" / Dialect(), "." + Dialect());
  ASSERT_GT(corpus.size(), 10u);
  for (auto& p : corpus) Replay(p);
}

}  // namespace
