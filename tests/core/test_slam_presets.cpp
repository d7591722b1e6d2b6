// presetDeviations (common/core/include/omnislam/core/slam/fastslam_options.h): derived from the options tables,
// it names every field of every table whose value differs from paper 000 as published, as
// "key=value" in the key's units with the part's prefix, and nothing else; paper 000 itself has none,
// and the recommended preset exactly the three deviations presetOptions() gives it.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "omnislam/core/angles.h"
#include "omnislam/core/slam/fastslam_options.h"
#include "omnislam/core/slam/options_table.h"

using namespace omnislam;
using namespace omnislam::slam;

namespace {

/// A value of the field other than the one in s (each kind changed its own way).
template <class S>
void changeField(const slam::options::Field<S>& f, S& s) {
  switch (f.kind) {
    case slam::options::Kind::kBool: ASSERT_EQ(f.setFlagMember(s, !f.flagMember(s)), nullptr) << f.key; break;
    case slam::options::Kind::kEnum: f.set_index(s, (f.get_index(s) + 1) % static_cast<int>(f.names->size())); break;
    case slam::options::Kind::kInt: s.*f.integer += 1; break;
    case slam::options::Kind::kReal: s.*f.real = std::isinf(s.*f.real) ? 10.0 : s.*f.real * 1.5 + 0.25; break;
    case slam::options::Kind::kVec3: (s.*f.vec3).x() += 0.25; break;
    default: FAIL() << f.key << ": a kind this test cannot change";
  }
}

/// For each field of the table: paper 000 with that field alone changed gives exactly one deviation,
/// "PREFIXkey=<its value>"; but `threads`, which changes no result, gives none.
template <class S, class PartOf>
void eachFieldAloneIsOneDeviation(const std::string& prefix, const std::vector<slam::options::Field<S>>& table,
                                  PartOf part_of) {
  for (const auto& f : table) {
    FastSlamOptions o = presetOptions(Preset::kPaper000);
    S& s = part_of(o);
    changeField(f, s);
    const std::vector<std::string> d = presetDeviations(o);
    if (prefix.empty() && std::string(f.key) == "threads") {
      EXPECT_TRUE(d.empty()) << "threads=" << slam::options::valueText(f, s);
      continue;
    }
    ASSERT_EQ(d.size(), 1u) << prefix << f.key;
    EXPECT_EQ(d[0], prefix + f.key + "=" + slam::options::valueText(f, s));
  }
}

TEST(PresetDeviations, PaperHasNoneAndRecommendedItsThree) {
  EXPECT_TRUE(presetDeviations(presetOptions(Preset::kPaper000)).empty());
  EXPECT_EQ(
      presetDeviations(presetOptions(Preset::kRecommended)),
      (std::vector<std::string>{"inflate_azimuth_near_zenith=true", "candidates.initial_cov_from_triangulation=true",
                                "candidates.refine_initial_point=true"}));
}

TEST(PresetDeviations, EveryFieldOfEveryTableIsCompared) {
  eachFieldAloneIsOneDeviation("", slam::options::fastSlamFields(),
                               [](FastSlamOptions& o) -> FastSlamOptions& { return o; });
  eachFieldAloneIsOneDeviation("motion.", slam::options::motionFields(),
                               [](FastSlamOptions& o) -> MotionNoiseOptions& { return o.motion; });
  eachFieldAloneIsOneDeviation("perception.", slam::options::perceptionFields(),
                               [](FastSlamOptions& o) -> PerceptionOptions& { return o.perception; });
  eachFieldAloneIsOneDeviation("candidates.", slam::options::candidateFields(),
                               [](FastSlamOptions& o) -> CandidateOptions& { return o.candidates; });
  eachFieldAloneIsOneDeviation("keyframes.", slam::options::keyframeFields(),
                               [](FastSlamOptions& o) -> KeyframeOptions& { return o.keyframes; });
}

TEST(PresetDeviations, ValuesInTheKeysUnitsAndNamesAndNoRoundingNoise) {
  FastSlamOptions o = presetOptions(Preset::kPaper000);
  o.weight_term = ConsistencyTerm{};
  o.resample_ess_fraction = 0.5;
  o.motion.model = MotionNoiseModel::kTranslateThenRotate;
  o.perception.azimuth_half_width_rad = deg2rad(34.4);
  o.perception.default_p_CinR_m = Eigen::Vector3d(0.0, 0.0, 1.8);
  // One bit off, as a value written in degrees and converted may be: the same value.
  o.candidates.min_parallax_rad = std::nextafter(o.candidates.min_parallax_rad, 1.0);
  EXPECT_EQ(presetDeviations(o),
            (std::vector<std::string>{"resample_ess_fraction=0.5", "weight_term=consistency",
                                      "motion.model=translate_then_rotate", "perception.azimuth_half_width_deg=34.4",
                                      "perception.default_camera_position_m=[0, 0, 1.8]"}));
}

}  // namespace
