// The SLAM process config (config/slam/*.yaml, common/config/include/omnislam/runtime/slam_config.h): the shipped file
// loads with the paper's values, and every mistake names its key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "omnislam/core/angles.h"
#include "omnislam/runtime/slam_config.h"
#include "omnislam/core/slam/options_table.h"

using namespace omnislam;
using namespace omnislam::runtime;

namespace {

const std::string kHall = std::string(OMNISLAM_SOURCE_DIR) + "/config/slam/sports_hall.yaml";

std::string readFile(const std::string& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

std::string errorOf(const std::string& text) {
  try {
    parseSlamOptions(config::Node::loadString(text, "slam.yaml"));
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(SlamConfig, ShippedSportsHallFileHasThePapersValues) {
  const SlamProcessOptions o = loadSlamOptions(kHall);
  EXPECT_EQ(o.validate(), "");
  EXPECT_EQ(o.filter.num_particles, 10);
  EXPECT_EQ(o.filter.association, slam::AssociationMethod::kHungarian);
  EXPECT_EQ(o.filter.p_new_mahalanobis_sq, 64.0);
  EXPECT_EQ(o.filter.candidates.nz_min, 3);
  EXPECT_EQ(o.filter.candidates.ncross_valid, 5);
  EXPECT_NEAR(o.filter.candidates.min_parallax_rad, deg2rad(7.0), 1e-12);
  EXPECT_EQ(o.filter.candidates.d_min_m, 8.0);
  EXPECT_EQ(o.filter.perception.detection_probability, 0.9);
  EXPECT_EQ(o.filter.perception.default_p_CinR_m, Eigen::Vector3d(0, 0, 1.8));
  EXPECT_EQ(o.pairing.max_wait_us, 2'000'000);
  EXPECT_EQ(o.pairing.max_odometry_gap_us, 500'000);
  EXPECT_EQ(o.pairing.restart_jump_us, 5'000'000);
  EXPECT_EQ(o.pairing.restart_confirm_messages, 2);
  EXPECT_EQ(o.pairing.max_odometry_speed_mps, 3.0);
  EXPECT_NEAR(o.pairing.max_odometry_yaw_rate_radps, deg2rad(344.0), 1e-12);
  EXPECT_EQ(o.start_source, SlamProcessOptions::StartSource::kFixed);
  EXPECT_EQ(o.start_pose_W.x_m, 6.0);  // the world file's trajectory start
  EXPECT_EQ(o.start_pose_W.y_m, -3.25);
  EXPECT_EQ(o.start_pose_W.theta_rad, 0.0);
  EXPECT_FALSE(o.use_vertical_lines);
  EXPECT_NEAR(o.min_sigma_rad, deg2rad(0.3), 1e-15);
  EXPECT_EQ(o.seed, 1u);
}

TEST(SlamConfig, EmptyFileGivesTheDefaults) {
  const SlamProcessOptions o = parseSlamOptions(config::Node::loadString("{}", "x"));
  EXPECT_EQ(o.validate(), "");
  EXPECT_EQ(o.filter.num_particles, slam::FastSlamOptions{}.num_particles);
}

TEST(SlamConfig, MlAssociationFixedStartAndSeed) {
  const SlamProcessOptions o = parseSlamOptions(config::Node::loadString(
      "seed: 7\nstart_pose: {source: fixed, x_m: 6.0, y_m: -3.25, theta_deg: 90}\nfilter: {association: ml, "
      "particles: 50}\n",
      "x"));
  EXPECT_EQ(o.seed, 7u);
  EXPECT_EQ(o.filter.association, slam::AssociationMethod::kMaximumLikelihood);
  EXPECT_EQ(o.filter.num_particles, 50);
  EXPECT_EQ(o.start_source, SlamProcessOptions::StartSource::kFixed);
  EXPECT_NEAR(o.start_pose_W.theta_rad, kPi / 2, 1e-12);
}

TEST(SlamConfig, CheckpointKeys) {
  const SlamProcessOptions off = parseSlamOptions(config::Node::loadString("{}", "x"));
  EXPECT_EQ(off.checkpoint_path, "");
  EXPECT_EQ(off.checkpoint_interval_us, 10'000'000);
  const std::string dir = ::testing::TempDir() + "slam_cfg_ckpt";
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/s.yaml") << "checkpoint: {path: run/state.ckpt, interval_s: 2.5}\n";
  const SlamProcessOptions o = loadSlamOptions(dir + "/s.yaml");
  EXPECT_EQ(o.checkpoint_path, (std::filesystem::path(dir) / "run/state.ckpt").lexically_normal().string())
      << "relative to the config file";
  EXPECT_EQ(o.checkpoint_interval_us, 2'500'000);
  EXPECT_NE(errorOf("checkpoint: {interval_s: 0}").find("checkpoint.interval_s"), std::string::npos)
      << errorOf("checkpoint: {interval_s: 0}");
  EXPECT_NE(errorOf("checkpoint: {every_s: 5}").find("every_s"), std::string::npos);
  std::filesystem::remove_all(dir);
}

// One name table serves the config key, --association and the start-up echo.
TEST(SlamConfig, AssociationNamesRoundTrip) {
  EXPECT_EQ(associationNames(), (std::vector<std::string>{"hungarian", "ml"}));
  EXPECT_EQ(associationFromName("hungarian"), slam::AssociationMethod::kHungarian);
  EXPECT_EQ(associationFromName("ml"), slam::AssociationMethod::kMaximumLikelihood);
  EXPECT_THROW(associationFromName("sampled"), std::invalid_argument);  // removed (docs/decisions.md)
  EXPECT_THROW(associationFromName("greedy"), std::invalid_argument);
  const SlamProcessOptions o = parseSlamOptions(config::Node::loadString("{}", "x"));
  EXPECT_NE(describe(o).find("filter: particles=10 association=hungarian proposal=fastslam2 "), std::string::npos)
      << describe(o);
}

TEST(SlamConfig, MistakesNameTheKey) {
  const std::string hall = readFile(kHall);
  struct Case {
    std::string from, to, key;
  };
  const Case cases[] = {
      {"particles: 10", "particles: 0", "filter.particles"},
      {"association: hungarian", "association: greedy", "filter.association"},
      // FastSLAM 1.0 already scores each pairing at its sampled pose
      {"association_predictive: true", "association_predictive: true\n  proposal: fastslam1",
       "key 'filter.association_predictive' needs proposal kFastSlam2"},
      {"nz_min: 3", "nz_min: three", "filter.candidates.nz_min"},
      {"min_parallax_deg: 7.0", "min_parallax_deg: 120", "filter.candidates.min_parallax_deg"},
      {"detection_probability: 0.9", "detection_probability: 1.5", "filter.perception.detection_probability"},
      // the core needs p_in < 1 and a half width > 0: refused at the file's own key, with the open end
      {"detection_probability: 0.9", "detection_probability: 1.0",
       "key 'filter.perception.detection_probability' must be a number in [0, 1), got 1.0"},
      {"azimuth_half_width_deg: 180.0", "azimuth_half_width_deg: 0",
       "key 'filter.perception.azimuth_half_width_deg' must be a number in (0, 180], got 0"},
      {"max_wait_s: 2.0", "max_wait_s: -1", "pairing.max_wait_s"},
      {"restart_confirm_messages: 2", "restart_confirm_messages: 0", "pairing.restart_confirm_messages"},
      {"odometry_buffer_s: 10.0", "odometry_buffer_s: 1.0",
       "key 'pairing.odometry_buffer_s' must be >= max_wait_s (2 s), got 1 s"},
      {"trans_sigma_per_sqrt_m: 0.05", "trans_sigm_per_sqrt_m: 0.05", "trans_sigm_per_sqrt_m"},
      {"source: fixed", "source: gps", "start_pose.source"},
      {"y_m: -3.25", "y_m: south", "start_pose.y_m"},
      {"map_every_n_frames: 1", "map_every_n_frames: 0", "output.map_every_n_frames"},
      {"min_sigma_deg: 0.3", "min_sigma_deg: -0.3", "features.min_sigma_deg"},
      {"min_sigma_deg: 0.3", "min_sigma_deg: 0.3\n  max_per_frame: 5000",
       "key 'features.max_per_frame' must be a whole number in [1, 4096], got 5000"},
      {"default_camera_position_m: [0.0, 0.0, 1.8]", "default_camera_position_m: [0.0, 1.8]",
       "default_camera_position_m"},
  };
  for (const auto& c : cases) {
    std::string text = hall;
    const auto pos = text.find(c.from);
    ASSERT_NE(pos, std::string::npos) << c.from;
    text.replace(pos, c.from.size(), c.to);
    const std::string err = errorOf(text);
    EXPECT_NE(err.find(c.key), std::string::npos) << c.to << " -> '" << err << "'";
    EXPECT_NE(err.find("slam.yaml"), std::string::npos) << err;
  }
}

}  // namespace

namespace {

// --set overrides: dotted keys into the file's maps (created when missing), values read as YAML,
// the same checks as in the file; a malformed override is named.
TEST(SlamConfig, OverridesApplyOnTopOfTheFile) {
  const std::string file = std::string(OMNISLAM_SOURCE_DIR) + "/config/slam/sports_hall.yaml";
  using omnislam::runtime::loadSlamOptions;
  const auto base = loadSlamOptions(file);
  const auto o = loadSlamOptions(file, {"filter.resample_ess_fraction=0.25", "filter.association=ml",
                                        "filter.perception.default_camera_position_m=[0, 0, 2]",
                                        "output.odometry_only_after_s=0", "map.save_path=/tmp/x.yaml"});
  EXPECT_EQ(o.filter.resample_ess_fraction, 0.25);
  EXPECT_EQ(o.filter.association, omnislam::slam::AssociationMethod::kMaximumLikelihood);
  EXPECT_EQ(o.filter.perception.default_p_CinR_m.z(), 2.0);
  EXPECT_EQ(o.odometry_only_after_us, 0);
  EXPECT_EQ(o.save_map_path, "/tmp/x.yaml");
  EXPECT_EQ(o.filter.num_particles, base.filter.num_particles) << "other keys as in the file";
  const auto err = [&](const std::string& ov) {
    try {
      loadSlamOptions(file, {ov});
    } catch (const omnislam::config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(err("filter.particles=0").find("filter.particles"), std::string::npos) << err("filter.particles=0");
  EXPECT_NE(err("filter.partcles=5").find("partcles"), std::string::npos);
  EXPECT_NE(err("filter.particles").find("dotted.key=value"), std::string::npos);
  EXPECT_NE(err("seed.x=1").find("'seed' is not a map"), std::string::npos) << err("seed.x=1");
  // A bad value set by an override names the override, not a line of the file it never was in.
  const std::string e0 = err("filter.particles=0");
  EXPECT_NE(e0.find("key 'filter.particles' must be a whole number in [1, 100000], got 0 (from the override "
                    "'filter.particles=0')"),
            std::string::npos)
      << e0;
  EXPECT_EQ(e0.find("(line"), std::string::npos) << e0;
  EXPECT_NE(err("filter.partcles=5").find("(from the override 'filter.partcles=5')"), std::string::npos)
      << err("filter.partcles=5");
  // A key inside a map that an override replaced, and the last of two overrides of one key.
  const std::string e1 = err("filter.motion={trans_sigma_per_sqrt_m: -1}");
  EXPECT_NE(e1.find("'filter.motion.trans_sigma_per_sqrt_m'"), std::string::npos) << e1;
  EXPECT_NE(e1.find("(from the override 'filter.motion={trans_sigma_per_sqrt_m: -1}')"), std::string::npos) << e1;
  try {
    loadSlamOptions(file, {"filter.particles=5", "filter.particles=-1"});
    ADD_FAILURE() << "particles=-1 accepted";
  } catch (const omnislam::config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("(from the override 'filter.particles=-1')"), std::string::npos) << e.what();
  }
}

// A bad value in the file itself still names its line when other keys are overridden.
TEST(SlamConfig, FileErrorsKeepTheirLineBesideOverrides) {
  const std::string src = std::string(OMNISLAM_SOURCE_DIR) + "/config/slam/sports_hall.yaml";
  std::string body = readFile(src);
  const auto at = body.find("  particles: ");
  ASSERT_NE(at, std::string::npos);
  const auto eol = body.find('\n', at);
  body.replace(at, eol - at, "  particles: -4");
  const int line = static_cast<int>(std::count(body.begin(), body.begin() + static_cast<long>(at), '\n')) + 1;
  const std::string file = ::testing::TempDir() + "/slam_config_bad_particles.yaml";
  std::ofstream(file) << body;
  try {
    omnislam::runtime::loadSlamOptions(file, {"filter.resample_ess_fraction=0.25"});
    ADD_FAILURE() << "particles: -4 accepted";
  } catch (const omnislam::config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("got -4 (line " + std::to_string(line) + ")"), std::string::npos) << e.what();
  }
}

// filter.preset: paper 000 as published (its Sec. IV values and no deviation), paper 002's
// variant, keys given beside a preset override it, and the echo names every deviation.
TEST(SlamConfig, PresetsSetDefaultsAndKeysOverride) {
  const auto load = [](const std::string& text) { return parseSlamOptions(config::Node::loadString(text, "x")); };
  const slam::FastSlamOptions p0 = load("filter: {preset: paper000}\n").filter;
  EXPECT_EQ(p0.num_particles, 10);
  EXPECT_TRUE(std::holds_alternative<slam::FastSlam2Proposal>(p0.proposal));
  EXPECT_EQ(p0.association, slam::AssociationMethod::kHungarian);
  EXPECT_EQ(p0.candidates.nz_min, 3);
  EXPECT_EQ(p0.candidates.ncross_valid, 5);
  EXPECT_NEAR(p0.candidates.min_parallax_rad, 7.0 * kPi / 180.0, 1e-3);
  EXPECT_EQ(p0.candidates.d_min_m, 8.0);
  EXPECT_EQ(p0.candidates.initial_cov_diag_m2, Eigen::Vector3d::Constant(0.0025));
  EXPECT_EQ(p0.p_new_mahalanobis_sq, 64.0);
  EXPECT_EQ(p0.resample_ess_fraction, 1.0);
  EXPECT_TRUE(slam::presetDeviations(p0).empty());
  EXPECT_NE(describe(load("filter: {preset: paper000}\n")).find("deviations from paper 000: none"), std::string::npos);

  const slam::FastSlamOptions p2 = load("filter: {preset: paper002}\n").filter;
  EXPECT_TRUE(std::holds_alternative<slam::FastSlam1Proposal>(p2.proposal));
  EXPECT_EQ(p2.association, slam::AssociationMethod::kMaximumLikelihood);
  EXPECT_EQ(p2.motion.model, slam::MotionNoiseModel::kTranslateThenRotate);
  const slam::FastSlamOptions p2_hungarian = load("filter: {preset: paper002, association: hungarian}\n").filter;
  EXPECT_EQ(p2_hungarian.association, slam::AssociationMethod::kHungarian);
  EXPECT_TRUE(std::holds_alternative<slam::FastSlam1Proposal>(p2_hungarian.proposal));

  const SlamProcessOptions rec = load("filter: {preset: recommended, association_predictive: true}\n");
  EXPECT_EQ(load("filter: {preset: recommended}\n").filter.candidates.refine_initial_point,
            slam::FastSlamOptions{}.candidates.refine_initial_point);
  const std::string echo = describe(rec);
  for (const char* d : {"inflate_azimuth_near_zenith=true", "association_predictive=true",
                        "candidates.initial_cov_from_triangulation=true", "candidates.refine_initial_point=true"}) {
    EXPECT_NE(echo.find(d), std::string::npos) << d << " in " << echo;
  }
  try {
    load("filter: {preset: paper001}\n");
    FAIL() << "an unknown preset was accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("filter.preset"), std::string::npos) << e.what();
  }
}

// The options tables drive the parser and the core's validation alike: every numeric key accepts
// its upper bound (its lower one when the upper is open), stored in the member's units, and refuses a value beyond it
// with its key named; the core refuses the member beyond its range with the field named; every default is in range.
// `companion` (a "key: value" of the same section) is written beside every other key: a value that
// other keys constrain (ncross_valid needs enough pairs of max_observations) is tested against it.
template <class S, class Get>
void expectTableDrivesParserAndCore(const std::string& section, const std::vector<slam::options::Field<S>>& table,
                                    Get member_of, const std::string& companion = "") {
  using slam::options::Kind;
  EXPECT_EQ(slam::options::checkRanges(S{}, table), "") << section;
  for (const auto& f : table) {
    if (f.kind != Kind::kReal && f.kind != Kind::kInt) continue;
    if (!std::isfinite(f.hi)) continue;  // an unlimited end: nothing beyond it
    const double edge = f.bounds == slam::options::Bounds::kHighOpen ? f.lo : f.hi;
    std::ostringstream ok, bad;
    const std::string with = companion.empty() || companion.rfind(f.key, 0) == 0 ? "" : ", " + companion;
    ok << "filter: {" << section << f.key << ": " << edge << with << "}" << std::string(section.empty() ? "" : "}")
       << "\n";
    bad << "filter: {" << section << f.key << ": " << (f.hi + 1.0) * 2.0 << with << "}"
        << std::string(section.empty() ? "" : "}") << "\n";
    const SlamProcessOptions o = parseSlamOptions(config::Node::loadString(ok.str(), "x"));
    const S& parsed = member_of(o);
    EXPECT_NEAR(f.value(parsed), edge, 1e-9 * std::max(1.0, std::abs(edge))) << f.key;
    try {
      parseSlamOptions(config::Node::loadString(bad.str(), "x"));
      ADD_FAILURE() << f.key << " accepted beyond its range";
    } catch (const config::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string(f.key) + "' must be"), std::string::npos) << e.what();
    }
    S beyond = parsed;
    if (f.kind == Kind::kReal) beyond.*f.real = f.memberHi() * 2.0 + 1.0;
    else beyond.*f.integer = static_cast<int>(f.hi) * 2 + 1;
    EXPECT_EQ(slam::options::checkRanges(beyond, table).rfind(std::string(f.field) + " must be in ", 0), 0u)
        << slam::options::checkRanges(beyond, table);
  }
}

TEST(SlamConfig, OptionsTablesDriveParserAndCore) {
  namespace opt = slam::options;
  expectTableDrivesParserAndCore("", opt::fastSlamFields(),
                                 [](const SlamProcessOptions& o) -> const slam::FastSlamOptions& { return o.filter; });
  expectTableDrivesParserAndCore(
      "motion: {", opt::motionFields(),
      [](const SlamProcessOptions& o) -> const slam::MotionNoiseOptions& { return o.filter.motion; });
  expectTableDrivesParserAndCore(
      "perception: {", opt::perceptionFields(),
      [](const SlamProcessOptions& o) -> const slam::PerceptionOptions& { return o.filter.perception; });
  expectTableDrivesParserAndCore(
      "candidates: {", opt::candidateFields(),
      [](const SlamProcessOptions& o) -> const slam::CandidateOptions& { return o.filter.candidates; },
      "max_observations: 1000");
}

}  // namespace
