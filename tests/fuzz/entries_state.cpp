// Fuzz entry points of the files a run reads back or imports: saved maps and checkpoints of the SLAM
// process (common/runtime map_file.cpp, checkpoint.cpp), the MRCLAM dataset's text files
// (tools/import_mrclam) and the wheel-data CSV of omnislam-odometry --source csv.
#include <algorithm>
#include <string>
#include <vector>

#include "csv_source.h"
#include "entry_points.h"
#include "guard.h"
#include "mrclam_files.h"
#include "omnislam/config/yaml_node.h"
#include "omnislam/core/byte_codec.h"
#include "omnislam/runtime/checkpoint.h"
#include "omnislam/runtime/map_file.h"
#include "omnislam/runtime/slam_driver.h"

namespace omnislam::fuzz {
namespace {

/// The options of the checkpoint seeds (fuzz_make_seeds): the defaults with 4 particles, so that
/// each input is fast; a checkpoint must have been written with the options it is read with.
runtime::SlamProcessOptions checkpointFuzzOptions() {
  runtime::SlamProcessOptions o;
  o.filter.num_particles = 4;
  return o;
}

/// decodeCheckpoint into a fresh driver and clock, then encodeCheckpoint of what was loaded.
std::vector<uint8_t> loadAndWrite(const std::vector<uint8_t>& file, const runtime::SlamProcessOptions& opt) {
  runtime::SlamDriver driver(opt);
  runtime::InputClock clock(opt.pairing.restart_jump_us);
  const runtime::ReplayPosition pos = runtime::decodeCheckpoint(file, opt, driver, clock);
  return runtime::encodeCheckpoint(opt, driver, clock, pos);
}

}  // namespace

void fuzzSavedMap(const uint8_t* data, size_t size) {
  const std::string path = scratchFile("saved_map", data, size);
  guard<config::ConfigError>("saved_map", [&] {
    const runtime::SavedMap m = runtime::loadMap(path);
    // A map that loads is written back byte for byte the same (mapToYaml is deterministic).
    const std::string yaml = runtime::mapToYaml(m);
    const std::string again = scratchFile("saved_map", reinterpret_cast<const uint8_t*>(yaml.data()), yaml.size());
    if (runtime::mapToYaml(runtime::loadMap(again)) != yaml)
      reportUnexpected("saved_map", "round trip", "a loaded map does not read back as written");
    const runtime::SlamDriver driver(checkpointFuzzOptions(), m.landmarks);  // --load-map's prior map
  });
}

void fuzzCheckpoint(const uint8_t* data, size_t size) {
  if (size == 0) return;
  // First byte odd: the rest is the whole file (its envelope fuzzed too). Even: the rest is the
  // payload, sealed here with a correct size and CRC so that the fuzzer reaches the state's decoding.
  const std::vector<uint8_t> rest(data + 1, data + size);
  const std::vector<uint8_t> file =
      (data[0] & 1) != 0 ? rest : sealState(runtime::kCheckpointMagic, runtime::kCheckpointVersion, rest);
  const runtime::SlamProcessOptions opt = checkpointFuzzOptions();
  guard<StateFormatError>("checkpoint", [&] {
    const std::vector<uint8_t> written = loadAndWrite(file, opt);
    // What a resumed run writes reads back as the same state: the second round trip is exact. (The
    // first may not be: e.g. the generator's state is text, and "0001" reads as "1".)
    std::vector<uint8_t> again;
    try {
      again = loadAndWrite(written, opt);
    } catch (const StateFormatError& e) {
      reportUnexpected("checkpoint", "round trip",
                       std::string("what a loaded checkpoint writes is refused: ") + e.what());
    }
    if (again != written) {
      const auto diff = std::mismatch(again.begin(), again.end(), written.begin(), written.end());
      reportUnexpected("checkpoint", "round trip",
                       "a checkpoint of " + std::to_string(written.size()) + " bytes is written back as " +
                           std::to_string(again.size()) + ", first difference at byte " +
                           std::to_string(diff.first - again.begin()));
    }
  });
}

void fuzzMrclam(const uint8_t* data, size_t size) {
  if (size == 0) return;
  const std::string path = scratchFile("mrclam", data + 1, size - 1);
  const auto dup = (data[0] & 8) != 0 ? mrclam::DuplicateTimes::kKeepLast : mrclam::DuplicateTimes::kError;
  guard<mrclam::ParseError>("mrclam", [&] {  // the first byte picks the file's kind
    mrclam::FileStats stats;
    switch (data[0] % 5) {
      case 0: (void)mrclam::readOdometry(path, dup, &stats); break;
      case 1: (void)mrclam::readGroundtruth(path, dup, &stats); break;
      case 2: (void)mrclam::readMeasurements(path, &stats); break;
      case 3: (void)mrclam::readLandmarks(path, &stats); break;
      default: (void)mrclam::readBarcodes(path, &stats); break;
    }
    (void)mrclam::describe(stats);
  });
}

void fuzzWheelCsv(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  guard<std::invalid_argument>("wheel_csv", [&] { (void)odometry::parseWheelCsv(text, "fuzz.csv"); });
}

}  // namespace omnislam::fuzz
