// Saved maps (common/runtime/include/omnislam/runtime/map_file.h): exact round trip, atomic replacement, and every
// malformed file refused with a message naming the file and the key.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>

#include "omnislam/runtime/map_file.h"
#include "omnislam/config/yaml_node.h"

using namespace omnislam;
using namespace omnislam::runtime;
namespace fs = std::filesystem;

namespace {

struct TmpDir {
  fs::path path;
  TmpDir() {
    path = fs::temp_directory_path() / ("omnislam_map_file_" + std::to_string(::getpid()));
    fs::create_directories(path);
  }
  ~TmpDir() { fs::remove_all(path); }
};

SavedMap sampleMap() {
  SavedMap m;
  m.utime = 1'700'000'123'456'789;
  for (int i = 0; i < 3; ++i) {
    slam::Landmark L;
    L.id = 10 + 7 * static_cast<std::uint64_t>(i);
    L.kind = i == 2 ? slam::LandmarkKind::kVerticalLine : slam::LandmarkKind::kPoint3D;
    L.type = i == 1 ? slam::LandmarkType::kTypeII : slam::LandmarkType::kTypeI;
    L.counter = 3 + i;
    L.p_LinW_m = Eigen::Vector3d(1.0 / 3.0 + i, -2.0e-7 * i, 6.5 + 0.1 * i);
    Eigen::Matrix3d A;
    A << 0.02, 0.001, 0.0, 0.001, 0.03, 1e-5, 0.0, 1e-5, 0.05 + i;
    L.cov_LinW_m2 = A;
    m.landmarks.push_back(L);
  }
  return m;
}

void writeText(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

std::string loadError(const fs::path& p) {
  try {
    loadMap(p.string());
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(MapFile, RoundTripIsExact) {
  TmpDir dir;
  const fs::path p = dir.path / "map.yaml";
  const SavedMap m = sampleMap();
  saveMapAtomically(m, p.string());
  const SavedMap r = loadMap(p.string());
  EXPECT_EQ(r.utime, m.utime);
  ASSERT_EQ(r.landmarks.size(), m.landmarks.size());
  for (std::size_t i = 0; i < m.landmarks.size(); ++i) {
    EXPECT_EQ(r.landmarks[i].id, m.landmarks[i].id);
    EXPECT_EQ(r.landmarks[i].kind, m.landmarks[i].kind);
    EXPECT_EQ(r.landmarks[i].type, m.landmarks[i].type);
    EXPECT_EQ(r.landmarks[i].counter, m.landmarks[i].counter);
    EXPECT_EQ(r.landmarks[i].p_LinW_m, m.landmarks[i].p_LinW_m) << "17 significant digits: bit-exact";
    EXPECT_EQ(r.landmarks[i].cov_LinW_m2, m.landmarks[i].cov_LinW_m2);
  }
  // Deterministic text, no temporary file left behind.
  EXPECT_EQ(mapToYaml(r), mapToYaml(m));
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir.path)) {
    ++files;
    EXPECT_EQ(e.path().filename(), "map.yaml");
  }
  EXPECT_EQ(files, 1);
  // An empty map round-trips too.
  saveMapAtomically(SavedMap{}, p.string());
  EXPECT_TRUE(loadMap(p.string()).landmarks.empty());
}

TEST(MapFile, SaveReplacesAtomicallyAndReportsUnwritablePaths) {
  TmpDir dir;
  const fs::path p = dir.path / "map.yaml";
  writeText(p, "old content that is not a map\n");
  saveMapAtomically(sampleMap(), p.string());
  EXPECT_EQ(loadMap(p.string()).landmarks.size(), 3u);
  try {
    saveMapAtomically(sampleMap(), (dir.path / "no_such_dir" / "map.yaml").string());
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_dir/map.yaml"), std::string::npos) << e.what();
  }
}

// SLAM_MAP carries at most 100 000 landmarks, so a bigger file is refused when it is loaded, before
// each landmark is read (empty items suffice to count).
TEST(MapFile, MoreLandmarksThanAMapMessageCarriesAreRefused) {
  TmpDir dir;
  const fs::path p = dir.path / "big.yaml";
  std::string text = "format: omnislam-map\nversion: 1\nlandmarks:\n";
  for (int i = 0; i <= 100000; ++i) text += "  - {}\n";
  writeText(p, text);
  const std::string e = loadError(p);
  EXPECT_NE(e.find("key 'landmarks' holds 100001 landmarks, more than 100000 (the most a map message carries)"),
            std::string::npos)
      << e;
}

TEST(MapFile, MalformedFilesNameFileAndKey) {
  TmpDir dir;
  const fs::path p = dir.path / "bad.yaml";
  const std::string head = "format: omnislam-map\nversion: 1\nutime: 5\nlandmarks:\n";
  const std::string good_cov = "covariance_m2: [1, 0, 0, 0, 1, 0, 0, 0, 1]";
  struct Case {
    std::string text, expect;
  } cases[] = {
      {"format: other\nversion: 1\nlandmarks: []\n", "format"},
      {"format: omnislam-map\nversion: 3\nlandmarks: []\n", "version"},
      {"format: omnislam-map\nversion: 1\nnum_landmarks: 0\nlandmarks: []\n", "num_landmarks"},
      {"format: omnislam-map\nversion: 1\n", "landmarks"},
      {head + "  - {id: 1, kind: blob, type: 1, counter: 1, position_m: [0, 0, 0], " + good_cov + "}\n", "kind"},
      {head + "  - {id: 1, kind: point3d, type: 3, counter: 1, position_m: [0, 0, 0], " + good_cov + "}\n", "type"},
      {head + "  - {id: 1, kind: point3d, type: 1, counter: 1, position_m: [0, .nan, 0], " + good_cov + "}\n",
       "position_m"},
      {head + "  - {id: 1, kind: point3d, type: 1, counter: 1, position_m: [0, 0], " + good_cov + "}\n", "position_m"},
      {head + "  - {id: 1, kind: point3d, type: 1, counter: 1, position_m: [0, 0, 0], covariance_m2: [1, 0, 0, 0, -1, "
              "0, 0, 0, 1]}\n",
       "covariance_m2"},
      {head + "  - {id: 1, kind: point3d, type: 1, counter: 1, position_m: [0, 0, 0], covariance_m2: [1, 0.5, 0, 0, 1, "
              "0, 0, 0, 1]}\n",
       "covariance_m2"},
      {head + "  - {id: 1, kind: point3d, type: 1, counter: 1, position_m: [0, 0, 0], " + good_cov + "}\n" +
           "  - {id: 1, kind: point3d, type: 1, counter: 1, position_m: [1, 0, 0], " + good_cov + "}\n",
       "duplicate"},
      {head + "  - {id: 1, kind: point3d, type: 1, counter: 1, position_m: [0, 0, 0], " + good_cov + ", colour: red}\n",
       "colour"},
  };
  for (const auto& c : cases) {
    writeText(p, c.text);
    const std::string err = loadError(p);
    EXPECT_NE(err.find("bad.yaml"), std::string::npos) << c.text << "\n-> " << err;
    EXPECT_NE(err.find(c.expect), std::string::npos) << c.text << "\n-> " << err;
  }
  EXPECT_NE(loadError(dir.path / "missing.yaml").find("missing.yaml"), std::string::npos);
}

// Issue 56, item 5: a file that is not a map at all (binary bytes, another YAML document) is refused
// naming the file and why. (Truncated files: the version 2 tests below.)
TEST(MapFile, ForeignFilesAreRefused) {
  TmpDir dir;
  const fs::path bin = dir.path / "foreign.bin";
  std::ofstream(bin, std::ios::binary) << std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16);
  EXPECT_NE(loadError(bin).find("foreign.bin"), std::string::npos);
  const fs::path other = dir.path / "world.yaml";
  writeText(other, "lights:\n  - [1, 2, 6.5]\ntrajectory: {}\n");
  const std::string err = loadError(other);
  EXPECT_NE(err.find("world.yaml"), std::string::npos) << err;
  EXPECT_NE(err.find("format"), std::string::npos) << err;
  // Neither is called a truncated map, nor is a missing file.
  EXPECT_EQ(err.find("truncated"), std::string::npos) << err;
  EXPECT_EQ(loadError(bin).find("truncated"), std::string::npos) << loadError(bin);
  EXPECT_EQ(loadError(dir.path / "missing.yaml").find("truncated"), std::string::npos);
}

// Version 2 (issue 56, item 5): the file cut at every byte offset is refused, naming the file; the
// whole file loads. Each refusal says why: truncated (no end line, or a count that disagrees), or
// the key the cut broke, with the missing end line named.
TEST(MapFile, EveryTruncationOfAVersion2MapIsRefused) {
  TmpDir dir;
  const fs::path p = dir.path / "cut.yaml";
  const std::string full = mapToYaml(sampleMap());
  ASSERT_NE(full.find("version: 2\n"), std::string::npos);
  ASSERT_NE(full.find("num_landmarks: 3\n"), std::string::npos);
  int named_truncated = 0;
  for (std::size_t cut = 0; cut < full.size(); ++cut) {
    writeText(p, full.substr(0, cut));
    const std::string err = loadError(p);
    ASSERT_FALSE(err.empty()) << "cut at byte " << cut << " of " << full.size() << " loaded";
    EXPECT_NE(err.find("cut.yaml"), std::string::npos) << cut << ": " << err;
    named_truncated += err.find("truncated") != std::string::npos;
  }
  EXPECT_EQ(named_truncated, static_cast<int>(full.size())) << "every refusal says the file may be truncated";
  writeText(p, full);
  EXPECT_EQ(loadMap(p.string()).landmarks.size(), 3u);
}

// A version 2 file whose count disagrees with its list (a landmark's line deleted) is refused;
// a version 1 file (no count, no end line) still loads.
TEST(MapFile, Version2CountIsCheckedAndVersion1StillLoads) {
  TmpDir dir;
  const fs::path p = dir.path / "map.yaml";
  const std::string full = mapToYaml(sampleMap());
  const std::size_t first = full.find("  - {id:");
  const std::size_t second = full.find("  - {id:", first + 1);
  writeText(p, full.substr(0, first) + full.substr(second));
  const std::string err = loadError(p);
  EXPECT_NE(err.find("num_landmarks"), std::string::npos) << err;
  EXPECT_NE(err.find("truncated"), std::string::npos) << err;

  std::string v1 = full;
  v1.replace(v1.find("version: 2"), 10, "version: 1");
  v1.erase(v1.find("num_landmarks: 3\n"), 17);
  v1.erase(v1.find("end: omnislam-map\n"));
  writeText(p, v1);
  const SavedMap m = loadMap(p.string());
  ASSERT_EQ(m.landmarks.size(), 3u);
  EXPECT_EQ(m.landmarks[2].id, sampleMap().landmarks[2].id);
}

}  // namespace
