// omnislam-eval: compares SLAM_POSE / SLAM_MAP of a log with GROUND_TRUTH_POSE / GROUND_TRUTH_MAP
// (from the same log or --truth) and prints a table, or one JSON object with --json. Landmarks are
// matched one-to-one by optimal assignment within --gate; unmatched estimates are spurious. No
// alignment unless --align (best rigid 2D transform of the trajectory onto the truth, applied to
// trajectory and map). Writes the SLAM, truth and (with ODOMETRY) dead-reckoning trajectories in TUM
// format for evo. Also: dead reckoning (ODOMETRY mapped into the truth frame by the start pose) raw
// and aligned, and, when the log has SLAM_ASSOCIATIONS and GROUND_TRUTH_FEATURE_LABELS, association
// precision / recall. A run the SLAM output covers only in part (fewer than --min-answered of the
// feature frames answered, or poses over less than --min-span of the run) is said on stderr and
// ends with exit code 3 unless --allow-incomplete.
#include <CLI/CLI.hpp>

#include <cmath>
#include <iostream>
#include <map>
#include <sstream>

#include "eval_log.h"
#include "eval_report.h"
#include "omnislam/eval/coverage.h"
#include "omnislam/eval/metrics.h"
#include "omnislam/lcmio/app.h"
#include "omnislam/lcmio/cli.h"

using namespace omnislam;
using namespace omnislam::evaltool;

namespace {

/// Exit code of a run scored but incomplete (the others are app::ExitCode: 0, 1, 2).
constexpr int kIncomplete = 3;

struct Options {
  std::string log, truth_log, tum_prefix, plot_prefix;
  bool json = false, align = false, no_tum = false, planar = false;
  double gate_m = 2.0;             ///< landmark matching gate
  eval::CoverageOptions coverage;  ///< minimum shares of a complete run (defaults 0.9, 0.9)
  bool allow_incomplete = false;   ///< exit 0 (with a warning) for an incomplete run
};

void addFlags(CLI::App& cli, Options& o) {
  cli.add_option("log", o.log, "log with SLAM_POSE and SLAM_MAP")->required()->check(CLI::ExistingFile);
  cli.add_option("--truth", o.truth_log, "log with GROUND_TRUTH_POSE and GROUND_TRUTH_MAP (default: the same log)")
      ->check(CLI::ExistingFile);
  cli.add_flag("--json", o.json, "print one JSON object instead of a table");
  cli.add_flag("--align", o.align, "fit the best rigid 2D transform of the trajectory onto the truth first");
  cli.add_option("--gate", o.gate_m, "landmark matching gate, metres")->check(app::FiniteRange(0.01, 100.0));
  cli.add_flag("--planar", o.planar, "landmark distances in x, y only (2D landmarks)");
  cli.add_option("--tum-out", o.tum_prefix,
                 "prefix of the TUM trajectory files PREFIX.slam.tum, .truth.tum and .odometry.tum (dead reckoning "
                 "in the truth frame; default: the log's path)");
  cli.add_flag("--no-tum", o.no_tum, "do not write TUM files");
  cli.add_option("--plot", o.plot_prefix, "write PREFIX.map.png (map and trajectories) and PREFIX.errors.png");
  cli.add_option("--min-answered", o.coverage.min_answered_share,
                 "least share of the OMNI_FEATURES frames with a SLAM_POSE for a complete run")
      ->capture_default_str()
      ->check(app::FiniteRange(0.0, 1.0));
  cli.add_option("--min-span", o.coverage.min_span_share,
                 "least share of the frames' span (the truth's without frames) the SLAM poses must cover")
      ->capture_default_str()
      ->check(app::FiniteRange(0.0, 1.0));
  cli.add_flag("--allow-incomplete", o.allow_incomplete,
               "exit 0 for an incomplete run (still said on stderr); without it such a run exits with code 3");
}

LogContent readLogs(const Options& o) {
  LogContent c;
  if (o.truth_log.empty()) {
    readLog(o.log, true, true, c);
  } else {
    readLog(o.log, true, false, c);
    readLog(o.truth_log, false, true, c);
  }
  for (const auto& [why, count] : c.skipped)
    std::cerr << "omnislam-eval: skipped " << count << " message" << (count == 1 ? "" : "s") << " of " << why << "\n";
  if (c.slam.empty()) throw std::invalid_argument(o.log + ": no SLAM_POSE message");
  if (c.truth.empty())
    throw std::invalid_argument((o.truth_log.empty() ? o.log : o.truth_log) + ": no GROUND_TRUTH_POSE message");
  return c;
}

/// The SLAM poses paired with the truth; none is an error (a 0 ATE would read as a perfect run).
std::vector<eval::PosePair> pairsOf(const LogContent& c) {
  auto pairs = eval::pairByTime(c.slam, c.truth);
  if (pairs.empty())
    throw std::invalid_argument(
        "no SLAM_POSE could be compared: none of the " + std::to_string(c.slam.size()) + " poses (utime " +
        std::to_string(c.slam.front().utime) + ".." + std::to_string(c.slam.back().utime) +
        ") lies between two GROUND_TRUTH_POSE at most 0.2 s apart (truth utime " +
        std::to_string(c.truth.front().utime) + ".." + std::to_string(c.truth.back().utime) + ")");
  return pairs;
}

/// --align: the best rigid transform of the paired poses onto the truth, applied to the pairs, the
/// SLAM trajectory and the SLAM map; refused (std::invalid_argument) when degenerate.
eval::Rigid2D alignOntoTruth(std::vector<eval::PosePair>& pairs, LogContent& c) {
  std::vector<Eigen::Vector2d> from, to;
  for (const auto& p : pairs) {
    from.emplace_back(p.estimate.x_m, p.estimate.y_m);
    to.emplace_back(p.truth.x_m, p.truth.y_m);
  }
  if (const std::string why = eval::rigidFitProblem(from, to); !why.empty())
    throw std::invalid_argument("--align: " + why);
  const auto T = eval::fitRigid2D(from, to);
  if (!T) throw std::invalid_argument("--align: the fitted transform is degenerate or not finite");
  for (auto& p : pairs) p.estimate = T->apply(p.estimate);
  for (auto& l : c.slam_map) l = T->apply(l);
  for (auto& p : c.slam) p.pose = T->apply(p.pose);
  for (auto& p : c.smoothed) p.pose = T->apply(p.pose);
  return *T;
}

eval::MapErrors mapErrorsOf(const LogContent& c, double gate_m, bool planar) {
  try {
    return eval::mapErrors(c.slam_map, c.truth_map, gate_m, planar);
  } catch (const std::invalid_argument& e) {  // a group too large to solve: name the flag
    std::ostringstream o;
    o << e.what() << " (--gate " << gate_m << " m)";
    throw std::invalid_argument(o.str());
  }
}

DeadReckoning deadReckoning(const LogContent& c) {
  DeadReckoning d;
  constexpr int64_t kMaxOdometryGapUs = 2'000'000;  // odometry loggers may pause (MRCLAM: 1 s)
  if (c.odometry.empty() || c.slam.empty()) return d;
  const int64_t t0 = c.slam.front().utime;
  const auto odom0 = eval::poseAt(c.odometry, t0, kMaxOdometryGapUs);
  const auto truth0 = eval::poseAt(c.truth, t0, 200'000);
  if (!odom0 || !truth0) return d;
  const eval::Rigid2D T0 = eval::rigidFromPoses(*odom0, *truth0);
  std::vector<eval::TimedPose> dr;
  for (const auto& p : c.slam)
    if (auto o = eval::poseAt(c.odometry, p.utime, kMaxOdometryGapUs)) dr.push_back({p.utime, T0.apply(*o)});
  auto pairs = eval::pairByTime(dr, c.truth);
  if (pairs.empty()) return d;
  d.poses = std::move(dr);
  d.available = true;
  d.raw = eval::trajectoryErrors(pairs);
  std::vector<Eigen::Vector2d> from, to;
  for (const auto& p : pairs) {
    from.emplace_back(p.estimate.x_m, p.estimate.y_m);
    to.emplace_back(p.truth.x_m, p.truth.y_m);
  }
  if (const auto T = eval::fitRigid2D(from, to))
    for (auto& p : pairs) p.estimate = T->apply(p.estimate);
  d.aligned = eval::trajectoryErrors(pairs);
  return d;
}

/// Association against the labels, with the landmark assignment of the map figures (me).
eval::AssociationScore associationScore(const LogContent& c, const eval::MapErrors& me) {
  std::map<int64_t, int64_t> truth_of_estimate;
  for (size_t i = 0; i < me.truth_of_estimate.size() && i < c.slam_map_ids.size(); ++i)
    if (me.truth_of_estimate[i] >= 0)
      truth_of_estimate[c.slam_map_ids[i]] = c.truth_map_ids[static_cast<size_t>(me.truth_of_estimate[i])];
  std::vector<std::vector<int64_t>> a, l;
  for (const auto& [u, lab] : c.labels) {
    const auto it = c.associations.find(u);
    if (it == c.associations.end()) continue;  // a frame the SLAM did not answer (dropped)
    a.push_back(it->second);
    l.push_back(lab);
  }
  return eval::scoreAssociations(a, l, truth_of_estimate);
}

/// Every figure printed is a number: a non-finite one is an error with its name, never "inf" or "-nan".
void requireFinite(const Scores& s) {
  const auto& te = s.te;
  const auto& me = s.me;
  std::vector<std::pair<const char*, double>> figures{{"ate_rmse_m", te.ate_rmse_m},
                                                      {"ate_max_m", te.ate_max_m},
                                                      {"heading_rmse_rad", te.heading_rmse_rad},
                                                      {"heading_max_rad", te.heading_max_rad},
                                                      {"landmark_mean_err_m", me.mean_err_m},
                                                      {"landmark_max_err_m", me.max_err_m}};
  for (double e : te.position_error_m) figures.push_back({"a position error", e});
  if (s.dr.available)
    figures.insert(figures.end(), {{"dr_ate_rmse_m", s.dr.raw.ate_rmse_m},
                                   {"dr_ate_max_m", s.dr.raw.ate_max_m},
                                   {"dr_heading_rmse_rad", s.dr.raw.heading_rmse_rad},
                                   {"dr_ate_rmse_aligned_m", s.dr.aligned.ate_rmse_m},
                                   {"dr_ate_max_aligned_m", s.dr.aligned.ate_max_m}});
  for (const auto& [name, v] : figures)
    if (!std::isfinite(v))
      throw std::invalid_argument(std::string(name) + " is not finite: positions too large to compare");
}

/// Every figure of the evaluation (c's SLAM trajectory and map are aligned in place with --align).
Scores score(const Options& o, LogContent& c) {
  Scores s;
  s.pairs = pairsOf(c);
  if (o.align) s.T = alignOntoTruth(s.pairs, c);
  s.te = eval::trajectoryErrors(s.pairs);
  s.me = mapErrorsOf(c, o.gate_m, o.planar);
  s.frames = c.feature_frames > 0 ? c.feature_frames : static_cast<int64_t>(c.slam.size());
  s.dr = deadReckoning(c);
  s.have_assoc = !c.associations.empty() && !c.labels.empty() && c.have_slam_map && c.have_truth_map;
  if (s.have_assoc) s.as = associationScore(c, s.me);
  std::vector<int64_t> pose_utimes, truth_utimes;
  for (const auto& p : c.slam) pose_utimes.push_back(p.utime);
  for (const auto& p : c.truth) truth_utimes.push_back(p.utime);
  s.coverage = eval::coverage(c.frame_utimes, pose_utimes, truth_utimes, o.coverage);
  if (const auto sp = eval::pairByTime(c.smoothed, c.truth); !sp.empty()) s.smoothed = eval::trajectoryErrors(sp);
  requireFinite(s);
  return s;
}

int evaluate(const Options& o) {
  LogContent c = readLogs(o);
  const Scores s = score(o, c);
  if (!o.no_tum) {
    const std::string prefix = o.tum_prefix.empty() ? o.log : o.tum_prefix;
    writeTum(prefix + ".slam.tum", c.slam);
    writeTum(prefix + ".truth.tum", c.truth);
    if (s.dr.available) writeTum(prefix + ".odometry.tum", s.dr.poses);
  }
  if (!o.plot_prefix.empty()) writePlots(s, c, o.log, o.plot_prefix);
  std::cout << (o.json ? jsonReport(s, c) : tableReport(s, c, o.log, o.gate_m)) << std::flush;
  if (s.coverage.complete()) return app::kOk;
  const std::string line = incompleteLine(s.coverage, o.coverage);
  if (o.allow_incomplete) {
    std::cerr << "omnislam-eval: warning: " << line << " (accepted: --allow-incomplete)" << std::endl;
    return app::kOk;
  }
  std::cerr << "omnislam-eval: " << line << " (exit code " << kIncomplete << "; --allow-incomplete accepts it)"
            << std::endl;
  return kIncomplete;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"omnislam-eval: SLAM estimate vs ground truth (ATE, heading, landmark errors)"};
  Options o;
  addFlags(cli, o);
  OMNISLAM_PARSE_FLAGS(cli, argc, argv);
  return app::runMain("omnislam-eval", [&]() -> int { return evaluate(o); });
}
