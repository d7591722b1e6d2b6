// The fuzz targets' saved inputs replayed in the normal suite (docs/design/fuzzing.md): every file of
// tests/fuzz/regressions/<target>/ (inputs that once crashed, hung, leaked or broke an oracle, kept
// after the fix) and of the seed corpus tests/fuzz/corpus/<target>/, through the same entry points
// as the libFuzzer executables. A finding aborts the test (under OMNISLAM_SANITIZE=1 a sanitizer
// report does too).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "entry_points.h"

namespace fs = std::filesystem;
using omnislam::fuzz::Target;

namespace omnislam::fuzz {
/// The test's parameter by its name in CTest's output.
void PrintTo(const Target& t, std::ostream* os) { *os << t.name; }
}  // namespace omnislam::fuzz

namespace {

const fs::path kFuzzDir = fs::path(OMNISLAM_SOURCE_DIR) / "tests" / "fuzz";

/// The files of a folder, sorted (none when it does not exist).
std::vector<fs::path> filesIn(const fs::path& dir) {
  std::vector<fs::path> out;
  if (fs::is_directory(dir))
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file()) out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<uint8_t> bytesOf(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

class FuzzRegressions : public ::testing::TestWithParam<Target> {
 protected:
  void SetUp() override {  // the readers that take a path get scratch files here, removed after
    const char* tmp = std::getenv("TMPDIR");
    saved_tmpdir_ = tmp ? std::optional<std::string>(tmp) : std::nullopt;
    scratch_ = fs::temp_directory_path() / ("omnislam-fuzz-test-" + std::string(GetParam().name));
    fs::create_directories(scratch_);
    ::setenv("TMPDIR", scratch_.c_str(), 1);
  }
  void TearDown() override {  // TMPDIR as it was: the next test's temp_directory_path() must exist
    if (saved_tmpdir_) ::setenv("TMPDIR", saved_tmpdir_->c_str(), 1);
    else ::unsetenv("TMPDIR");
    fs::remove_all(scratch_);
  }
  fs::path scratch_;
  std::optional<std::string> saved_tmpdir_;
};

TEST_P(FuzzRegressions, SavedInputsAndSeedsAreRefusedOrAcceptedWithoutAFinding) {
  const Target& t = GetParam();
  const auto seeds = filesIn(kFuzzDir / "corpus" / t.name);
  EXPECT_FALSE(seeds.empty()) << "no seed corpus for " << t.name;
  std::vector<fs::path> inputs = filesIn(kFuzzDir / "regressions" / t.name);
  inputs.insert(inputs.end(), seeds.begin(), seeds.end());
  for (const fs::path& p : inputs) {
    SCOPED_TRACE(p.string());
    const std::vector<uint8_t> bytes = bytesOf(p);
    t.entry(bytes.data(), bytes.size());  // aborts on a finding
  }
  RecordProperty("inputs", static_cast<int>(inputs.size()));
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzRegressions, ::testing::ValuesIn(omnislam::fuzz::targets()),
                         [](const ::testing::TestParamInfo<Target>& i) { return std::string(i.param.name); });

}  // namespace
