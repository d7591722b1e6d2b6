// omnislam-eval's outputs (eval_report.h): JSON, table, the incomplete-run line, TUM files, plots.
#include "eval_report.h"

#include <Eigen/Geometry>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "omnislam/runtime/atomic_file.h"
#include "omnislam/vision/plots.h"

namespace omnislam::evaltool {

namespace {

/// A ratio for the table: "n/a" when its denominator is 0 (nothing to score), never a 0.
std::string ratioText(double ratio, int64_t denominator) {
  if (denominator == 0) return "n/a";
  std::ostringstream o;
  o << std::setprecision(6) << ratio;
  return o.str();
}

/// A share in [0, 1] as a percentage with one decimal ("34.6 %").
std::string percent(double share) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(1) << 100.0 * share << " %";
  return o.str();
}

/// Seconds with two decimals ("210.26 s").
std::string seconds(double s) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(2) << s << " s";
  return o.str();
}

void coverageJson(std::ostream& o, const eval::Coverage& v) {
  o << ", \"complete\": " << (v.complete() ? "true" : "false") << ", \"frames_answered\": " << v.frames_answered
    << ", \"answered_share\": " << v.answered_share << ", \"coverage_reference\": \""
    << (v.reference_is_frames ? "frames" : "truth") << "\", \"reference_span_s\": " << v.reference_span_s
    << ", \"pose_span_s\": " << v.pose_span_s << ", \"span_share\": " << v.span_share
    << ", \"pose_start_gap_s\": " << v.start_gap_s << ", \"pose_end_gap_s\": " << v.end_gap_s
    << ", \"truth_span_s\": " << v.truth_span_s << ", \"truth_end_gap_s\": " << v.truth_end_gap_s;
}

void optionalJson(std::ostream& o, const Scores& s) {
  o << ", \"dr_available\": " << (s.dr.available ? "true" : "false");
  if (s.dr.available)
    o << ", \"dr_ate_rmse_m\": " << s.dr.raw.ate_rmse_m << ", \"dr_ate_max_m\": " << s.dr.raw.ate_max_m
      << ", \"dr_heading_rmse_rad\": " << s.dr.raw.heading_rmse_rad
      << ", \"dr_ate_rmse_aligned_m\": " << s.dr.aligned.ate_rmse_m
      << ", \"dr_ate_max_aligned_m\": " << s.dr.aligned.ate_max_m << ", \"dr_poses_compared\": " << s.dr.raw.pairs;
  o << ", \"smoothed_available\": " << (s.smoothed ? "true" : "false");
  if (s.smoothed)
    o << ", \"smoothed_ate_rmse_m\": " << s.smoothed->ate_rmse_m
      << ", \"smoothed_ate_max_m\": " << s.smoothed->ate_max_m
      << ", \"smoothed_heading_rmse_rad\": " << s.smoothed->heading_rmse_rad
      << ", \"smoothed_poses_compared\": " << s.smoothed->pairs;
  o << ", \"assoc_available\": " << (s.have_assoc ? "true" : "false");
  if (s.have_assoc) {
    const auto& as = s.as;
    o << ", \"assoc_precision\": " << as.precision() << ", \"assoc_recall\": " << as.recall()
      << ", \"assoc_frames\": " << as.frames << ", \"assoc_frames_mismatched\": " << as.frames_mismatched
      << ", \"assoc_features\": " << as.features << ", \"assoc_true_landmark_features\": " << as.true_landmark_features
      << ", \"assoc_associated\": " << as.associated << ", \"assoc_correct\": " << as.correct
      << ", \"assoc_clutter_associated\": " << as.clutter_associated;
  }
}

/// The table's coverage line: frames answered, the reference span covered, where the truth ends.
std::string coverageText(const eval::Coverage& v) {
  std::ostringstream o;
  o << "  coverage: ";
  if (v.frames > 0)
    o << v.frames_answered << " of " << v.frames << " frames answered (" << percent(v.answered_share) << "); ";
  o << "poses cover " << percent(v.span_share) << " of the " << (v.reference_is_frames ? "frames'" : "truth's")
    << " span of " << seconds(v.reference_span_s);
  if (v.truth_span_s > 0) {
    if (v.truth_end_gap_s >= 0) o << "; the truth ends " << seconds(v.truth_end_gap_s) << " after the last pose";
    else o << "; the last pose is " << seconds(-v.truth_end_gap_s) << " after the truth's end";
  }
  o << (v.complete() ? "" : "  INCOMPLETE") << "\n";
  return o.str();
}

void tableMapLines(std::ostream& o, const Scores& s, const LogContent& c, double gate_m) {
  const auto& me = s.me;
  if (!c.have_truth_map) {  // nothing to compare with: no "0 true" and no 0 m error
    o << "  map: " << me.estimated << " estimated; no truth map (no GROUND_TRUTH_MAP)\n";
    return;
  }
  o << "  map: " << me.estimated << " estimated, " << me.truth << " true, " << me.matched << " matched within "
    << gate_m << " m, " << me.spurious << " spurious\n";
  if (me.matched > 0) o << "    landmark error mean " << me.mean_err_m << " m, max " << me.max_err_m << " m\n";
  else o << "    landmark error n/a (no landmark matched)\n";
}

void tableOptionalLines(std::ostream& o, const Scores& s) {
  if (s.T)
    o << "  alignment: rotation " << s.T->theta_rad << " rad, translation (" << s.T->t_m.x() << ", " << s.T->t_m.y()
      << ") m\n";
  const auto& dr = s.dr;
  if (dr.available)
    o << "  dead reckoning (ODOMETRY from the start pose): ATE RMSE " << dr.raw.ate_rmse_m << " m, max "
      << dr.raw.ate_max_m << " m; aligned: RMSE " << dr.aligned.ate_rmse_m << " m, max " << dr.aligned.ate_max_m
      << " m\n";
  if (s.smoothed)
    o << "  smoothed keyframes (the back end's last SLAM_TRAJECTORY): " << s.smoothed->pairs << " compared, ATE RMSE "
      << s.smoothed->ate_rmse_m << " m, max " << s.smoothed->ate_max_m << " m, heading RMSE "
      << s.smoothed->heading_rmse_rad << " rad\n";
  if (s.have_assoc) {
    const auto& as = s.as;
    o << "  association: precision " << ratioText(as.precision(), as.associated) << " (" << as.correct << "/"
      << as.associated << "), recall " << ratioText(as.recall(), as.true_landmark_features) << " (" << as.correct << "/"
      << as.true_landmark_features << "); " << as.clutter_associated << " clutter features associated; " << as.frames
      << " frames, " << as.frames_mismatched << " left out (feature counts differ)\n";
  }
}

}  // namespace

std::string jsonReport(const Scores& s, const LogContent& c) {
  std::ostringstream o;
  o << std::setprecision(6);
  const auto& te = s.te;
  const auto& me = s.me;
  o << "{\"ate_rmse_m\": " << te.ate_rmse_m << ", \"ate_max_m\": " << te.ate_max_m
    << ", \"heading_rmse_rad\": " << te.heading_rmse_rad << ", \"heading_max_rad\": " << te.heading_max_rad
    << ", \"landmark_mean_err_m\": " << me.mean_err_m << ", \"landmark_max_err_m\": " << me.max_err_m
    << ", \"landmarks_matched\": " << me.matched << ", \"landmarks_truth\": " << me.truth
    << ", \"landmarks_estimated\": " << me.estimated << ", \"landmarks_spurious\": " << me.spurious
    << ", \"frames\": " << s.frames << ", \"frames_with_pose\": " << c.slam.size()
    << ", \"poses_compared\": " << te.pairs << ", \"messages_skipped\": " << c.skippedTotal()
    << ", \"log_unreadable_bytes\": " << c.unreadable_bytes;
  coverageJson(o, s.coverage);
  o << ", \"aligned\": " << (s.T ? "true" : "false");
  if (s.T)
    o << ", \"align_theta_rad\": " << s.T->theta_rad << ", \"align_tx_m\": " << s.T->t_m.x()
      << ", \"align_ty_m\": " << s.T->t_m.y();
  o << ", \"map_available\": " << (c.have_slam_map && c.have_truth_map ? "true" : "false");
  optionalJson(o, s);
  o << "}\n";
  return o.str();
}

std::string tableReport(const Scores& s, const LogContent& c, const std::string& log, double gate_m) {
  std::ostringstream o;
  o << std::setprecision(6);
  o << "omnislam-eval " << log << (s.T ? "  (aligned)" : "") << "\n";
  if (c.unreadable_bytes > 0)
    o << "  the log's last " << c.unreadable_bytes << " bytes cannot be read (truncated or corrupt; stderr)\n";
  if (c.skippedTotal() > 0)
    o << "  skipped " << c.skippedTotal() << " undecodable, invalid or replaced messages (listed on stderr)\n";
  o << "  trajectory: " << s.te.pairs << " poses compared of " << c.slam.size() << " (" << s.frames << " frames)\n";
  o << "    ATE RMSE " << s.te.ate_rmse_m << " m, max " << s.te.ate_max_m << " m\n";
  o << "    heading RMSE " << s.te.heading_rmse_rad << " rad, max " << s.te.heading_max_rad << " rad\n";
  o << coverageText(s.coverage);
  tableMapLines(o, s, c, gate_m);
  tableOptionalLines(o, s);
  return o.str();
}

std::string incompleteLine(const eval::Coverage& v, const eval::CoverageOptions& opt) {
  std::ostringstream o;
  o << "INCOMPLETE RUN: ";
  if (v.frames > 0)
    o << "the SLAM answered " << v.frames_answered << " of " << v.frames << " frames (" << percent(v.answered_share)
      << (v.answered_ok ? " >= " : " < ") << "--min-answered " << percent(opt.min_answered_share) << "); ";
  o << "its poses cover " << percent(v.span_share) << " of the " << (v.reference_is_frames ? "frames'" : "truth's")
    << " span of " << seconds(v.reference_span_s) << (v.span_ok ? " (>= " : " (< ") << "--min-span "
    << percent(opt.min_span_share) << "): they start " << seconds(v.start_gap_s) << " after it and end "
    << seconds(v.end_gap_s) << " before it; the figures describe only that part of the run";
  return o.str();
}

void writeTum(const std::string& path, const std::vector<eval::TimedPose>& poses) {
  std::ostringstream f;
  f << "# timestamp_s x_m y_m z_m qx qy qz qw\n" << std::setprecision(17);
  for (const auto& p : poses)
    f << p.utime * 1e-6 << " " << p.pose.x_m << " " << p.pose.y_m << " 0 0 0 " << std::sin(0.5 * p.pose.theta_rad)
      << " " << std::cos(0.5 * p.pose.theta_rad) << "\n";
  const std::string text = f.str();
  runtime::writeFileAtomically(path, text.data(), text.size());
}

void writePlots(const Scores& s, const LogContent& c, const std::string& log, const std::string& prefix) {
  vision::MapPlot mp;
  mp.title = log + (s.T ? "  (aligned)" : "");
  for (const auto& p : c.slam) mp.estimate.push_back(p.pose);
  for (const auto& p : c.truth) mp.truth.push_back(p.pose);
  for (size_t i = 0; i < c.slam_map.size(); ++i) {
    vision::PlotLandmark l;
    l.p_m = c.slam_map[i];
    if (i < c.slam_map_cov_xy.size()) {
      Eigen::Matrix2d cov = c.slam_map_cov_xy[i];
      if (s.T) {  // rotate the covariance with the alignment
        const Eigen::Matrix2d R = Eigen::Rotation2Dd(s.T->theta_rad).toRotationMatrix();
        cov = R * cov * R.transpose();
      }
      l.cov_xy_m2 = cov;
    }
    mp.estimated_landmarks.push_back(l);
  }
  mp.true_landmarks = c.truth_map;
  vision::ErrorPlot ep;
  ep.title = "errors over time";
  for (size_t i = 0; i < s.pairs.size(); ++i) {
    ep.t_s.push_back((s.pairs[i].utime - s.pairs.front().utime) * 1e-6);
    ep.position_err_m.push_back(s.te.position_error_m[i]);
    ep.heading_err_rad.push_back(s.te.heading_error_rad[i]);
  }
  if (!cv::imwrite(prefix + ".map.png", vision::renderMapPlot(mp)) ||
      !cv::imwrite(prefix + ".errors.png", vision::renderErrorPlot(ep)))
    throw std::runtime_error("--plot: cannot write PNG files with prefix '" + prefix + "'");
}

}  // namespace omnislam::evaltool
