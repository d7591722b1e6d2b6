// The fuzz targets' entry points (docs/design/fuzzing.md): every place where bytes from outside enter
// the project, called exactly as the process or tool that reads them does. Shared by the libFuzzer
// executables (fuzz_target.cpp, OMNISLAM_FUZZ=ON) and the regression test of the normal suite
// (test_fuzz_regressions.cpp), which replays the saved inputs through the same functions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace omnislam::fuzz {

/// One entry point: consumes any bytes. Refusing them (a returned reason, or one of the exceptions
/// the reader documents: config::ConfigError, StateFormatError, ...) is the expected outcome; any
/// other exception is a finding and aborts (reportUnexpected), as a crash or a sanitizer report does.
using EntryPoint = void (*)(const uint8_t* data, size_t size);

struct Target {
  const char* name;    ///< the executable is fuzz_<name>; the corpus tests/fuzz/corpus/<name>/
  EntryPoint entry;    ///< the code under test
  const char* covers;  ///< one line: what it calls (for docs and the test's messages)
};

/// Every target, in the order scripts/fuzz.sh runs them.
const std::vector<Target>& targets();

/// The target called `name`, or nullptr.
const Target* findTarget(const std::string& name);

/// Prints "fuzz: TARGET: unexpected exception TYPE: WHAT" to stderr and aborts.
[[noreturn]] void reportUnexpected(const char* target, const char* type, const std::string& what);

/// Writes the bytes to this process's scratch file for `target` (under $TMPDIR, else /tmp) for the
/// readers that take a path; returns the path. The file is overwritten by the next input.
std::string scratchFile(const char* target, const uint8_t* data, size_t size);

// The entry points, by source file.
void fuzzLcmMessages(const uint8_t* data, size_t size);  // entries_lcm.cpp
void fuzzLcmLog(const uint8_t* data, size_t size);
void fuzzImageHeader(const uint8_t* data, size_t size);  // entries_image.cpp
void fuzzImageDecode(const uint8_t* data, size_t size);
void fuzzCalibration(const uint8_t* data, size_t size);
void fuzzOcamCalib(const uint8_t* data, size_t size);
void fuzzSlamConfig(const uint8_t* data, size_t size);  // entries_config.cpp
void fuzzWorldConfig(const uint8_t* data, size_t size);
void fuzzFeaturesConfig(const uint8_t* data, size_t size);
void fuzzLaunchFile(const uint8_t* data, size_t size);
void fuzzSavedMap(const uint8_t* data, size_t size);  // entries_state.cpp
void fuzzCheckpoint(const uint8_t* data, size_t size);
void fuzzMrclam(const uint8_t* data, size_t size);
void fuzzWheelCsv(const uint8_t* data, size_t size);

}  // namespace omnislam::fuzz
