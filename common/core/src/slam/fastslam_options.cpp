// The filter's options: validation, presets, the deviations from paper 000 and the mapping to the
// variant types (fastslam_options.h).
#include "omnislam/core/slam/fastslam_options.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <variant>

#include "omnislam/core/slam/options_table.h"
#include "omnislam/core/slam/validation.h"

namespace omnislam::slam {

namespace {

/// Equal up to the rounding of a unit conversion (a value a config writes in degrees is converted to
/// radians and may differ from the same value in the code in the last bit). An infinite value equals
/// only itself.
bool sameValue(double a, double b) {
  if (a == b) return true;
  return std::isfinite(a) && std::isfinite(b) && std::abs(a - b) <= 1e-12 * std::max(std::abs(a), std::abs(b));
}

/// "PREFIXkey=value" (the key's units, as a config writes it) of every field of the table in which
/// `now` differs from `paper`, in the table's order.
template <class S>
void appendDifferences(const std::string& prefix, const S& now, const S& paper,
                       const std::vector<options::Field<S>>& table, std::vector<std::string>& out) {
  for (const auto& f : table) {
    bool same = true;
    if (f.kind == options::Kind::kVec3) {
      for (int i = 0; i < 3; ++i) same = same && sameValue((now.*f.vec3)(i), (paper.*f.vec3)(i));
    } else {
      same = sameValue(f.value(now), f.value(paper));
    }
    if (!same) out.push_back(prefix + f.key + "=" + options::valueText(f, now));
  }
}

}  // namespace

std::string FastSlamOptions::validate() const {
  const std::string ranges = options::checkRanges(*this, options::fastSlamFields());  // options_table.h
  if (!ranges.empty()) return ranges;
  detail::FieldChecker c;
  c.nested("motion", motion.validate())
      .nested("perception", perception.validate())
      .nested("candidates", candidates.validate())
      .nested("keyframes", options::checkRanges(keyframes, options::keyframeFields()));
  return c.message();
}

stages::FilterVariant filterVariantOf(const FastSlamOptions& o) {
  const std::string msg = o.validate();
  if (!msg.empty()) throw std::invalid_argument("FastSlamOptions: " + msg);
  const stages::DeterministicAssociation association =
      o.association == AssociationMethod::kMaximumLikelihood
          ? stages::DeterministicAssociation{stages::MaximumLikelihoodAssociation{}}
          : stages::DeterministicAssociation{stages::HungarianAssociation{}};
  return std::visit(stages::Overloaded{[&](const FastSlam1Proposal&) -> stages::FilterVariant {
                                         return stages::FastSlam1{association};
                                       },
                                       [&](const FastSlam2Proposal& p) -> stages::FilterVariant {
                                         return stages::FastSlam2{association, p.pair_score, p.weight};
                                       }},
                    o.proposal);
}

FastSlamOptions presetOptions(Preset preset) {
  FastSlamOptions o;  // kRecommended: the in-class defaults
  if (preset == Preset::kRecommended) return o;
  // Both papers: the measurement covariance as published, Sigma_0 fixed, the chosen cross-point as is.
  o.inflate_azimuth_near_zenith = false;
  o.candidates.initial_cov_from_triangulation = false;
  o.candidates.refine_initial_point = false;
  if (preset == Preset::kPaper000) return o;
  // Paper 002: FastSLAM 1.0 ("traditional FastSLAM"), maximum likelihood per measurement (Sec. III-D),
  // the translate-then-rotate odometry model (Sec. III-C), a 2D Gaussian triangulation error model.
  o.proposal = FastSlam1Proposal{};
  o.association = AssociationMethod::kMaximumLikelihood;
  o.motion.model = MotionNoiseModel::kTranslateThenRotate;
  o.candidates.initial_cov_from_triangulation = true;
  return o;
}

const std::vector<std::string>& presetNames() {
  static const std::vector<std::string> names{"recommended", "paper000", "paper002"};  // index = Preset
  return names;
}

std::vector<std::string> presetDeviations(const FastSlamOptions& o) {
  FastSlamOptions p = presetOptions(Preset::kPaper000);
  p.threads = o.threads;  // the thread count changes no result: not a deviation
  std::vector<std::string> out;
  appendDifferences("", o, p, options::fastSlamFields(), out);
  appendDifferences("motion.", o.motion, p.motion, options::motionFields(), out);
  appendDifferences("perception.", o.perception, p.perception, options::perceptionFields(), out);
  appendDifferences("candidates.", o.candidates, p.candidates, options::candidateFields(), out);
  appendDifferences("keyframes.", o.keyframes, p.keyframes, options::keyframeFields(), out);
  return out;
}

}  // namespace omnislam::slam
