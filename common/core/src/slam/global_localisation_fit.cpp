// Global localisation (global_localisation.h), step 3: one pose against one frame. The lamps predicted
// inside the perceptual range, the bearings assigned to them one to one within a chi-square gate, the
// frame's log-likelihood ratio against clutter, and Gauss-Newton on the matched bearings (with the
// prediction as a prior for a tracked hypothesis: an iterated EKF update).
#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/global_localisation.h"
#include "omnislam/core/slam/hungarian.h"

namespace omnislam::slam {

struct GlobalLocaliser::Predicted {
  int lamp = 0;
  Eigen::Vector2d z = Eigen::Vector2d::Zero();  ///< predicted (azimuth, elevation) [rad]
  Eigen::Matrix<double, 2, 3> H = Eigen::Matrix<double, 2, 3>::Zero();
  Eigen::Matrix2d R_lamp = Eigen::Matrix2d::Zero();  ///< the lamp's map covariance in bearing space
  bool expected = false;                             ///< inside the unwidened range: a miss counts log(1 - P_D)
  /// Expected and the association margin inside both ranges: its miss counts in c (a map error
  /// smaller than the margin cannot take the lamp out of range for one pose and not its twin).
  bool inner = false;
};

namespace {

Eigen::Vector3d cameraOffset(const std::vector<BearingMeasurement>& z, const PerceptionOptions& perception) {
  for (const BearingMeasurement& m : z)
    if (m.kind == LandmarkKind::kPoint3D) return m.p_CinR_m;
  return perception.default_p_CinR_m;
}

Eigen::Matrix2d bearingCovariance(const BearingMeasurement& m) {
  const MeasMat Q = measurementCovariance(m, true);
  return Q.topLeftCorner<2, 2>();
}

Eigen::Vector2d bearingInnovation(const BearingMeasurement& m, const Eigen::Vector2d& zhat) {
  return {wrapAngle(m.azimuth_rad - zhat.x()), wrapAngle(m.elevation_rad - zhat.y())};
}

bool usable(const BearingMeasurement& m) {
  return m.kind == LandmarkKind::kPoint3D && std::isfinite(m.azimuth_rad) && std::isfinite(m.elevation_rad) &&
         m.cov_rad2.allFinite() && m.p_CinR_m.allFinite();
}

}  // namespace

std::vector<GlobalLocaliser::Predicted> GlobalLocaliser::predictVisible(const Pose2& pose_W,
                                                                        const Eigen::Vector3d& p_CinR_m) const {
  const Eigen::Vector2d centre = cameraCentreInWorld(pose_W, p_CinR_m).head<2>();
  // Lamps up to the association margin beyond max_range_m may match a bearing (a lamp just beyond it
  // for one pose, just inside for its twin: the map's errors must not decide between them); only
  // those within max_range_m are expected, a miss counted.
  std::vector<int> near;
  index_.lampsNear(centre, opt_.max_range_m + perception_.association_margin_m, near);
  std::vector<Predicted> out;
  out.reserve(near.size());
  for (int i : near) {
    const Eigen::Vector3d& p = index_.lamp(i);
    if (!insidePerceptualRange(p, LandmarkKind::kPoint3D, pose_W, p_CinR_m, perception_,
                               perception_.association_margin_rad, perception_.association_margin_m))
      continue;
    Predicted pr;
    pr.lamp = i;
    Eigen::Matrix<double, 2, 3> J_l;
    const auto z = predictBearing(p, pose_W, p_CinR_m, &pr.H, &J_l);
    if (!z) continue;
    pr.R_lamp = J_l * index_.lampCov(i) * J_l.transpose();
    pr.z = *z;
    pr.expected = probabilityInside(p, LandmarkKind::kPoint3D, pose_W, p_CinR_m, perception_) > 0.0 &&
                  (p.head<2>() - centre).norm() <= opt_.max_range_m;
    const double margin_m = perception_.association_margin_m;
    pr.inner = pr.expected && (p.head<2>() - centre).norm() <= opt_.max_range_m - margin_m &&
               (p - cameraCentreInWorld(pose_W, p_CinR_m)).norm() <= perception_.max_range_m - margin_m;
    out.push_back(pr);
  }
  return out;
}

int GlobalLocaliser::expectedInside(const Pose2& pose_W, const std::vector<BearingMeasurement>& z) const {
  const std::vector<Predicted> lamps = predictVisible(pose_W, cameraOffset(z, perception_));
  return static_cast<int>(std::count_if(lamps.begin(), lamps.end(), [](const Predicted& p) { return p.inner; }));
}

std::vector<int> GlobalLocaliser::assign(const std::vector<Predicted>& lamps, const Eigen::Matrix3d& P,
                                         const std::vector<BearingMeasurement>& z, double* llr, double* count_llr,
                                         int* matched) const {
  const double log_pd = std::log(perception_.detection_probability);
  const double log_miss = std::log(std::max(1.0 - perception_.detection_probability, 1e-12));
  Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(z.size()),
                                                   static_cast<Eigen::Index>(lamps.size()), kForbiddenCost);
  // Within the counts' wider gate, for c (countMatches).
  Eigen::MatrixXd near = Eigen::MatrixXd::Constant(cost.rows(), cost.cols(), kForbiddenCost);
  for (std::size_t i = 0; i < z.size(); ++i) {
    if (!usable(z[i])) continue;
    const Eigen::Matrix2d Q = bearingCovariance(z[i]);
    for (std::size_t j = 0; j < lamps.size(); ++j) {
      const Eigen::Matrix2d S = lamps[j].H * P * lamps[j].H.transpose() + lamps[j].R_lamp + Q;
      // log N(r; 0, S) of the 2x2 in closed form (the gate first: most pairs are far outside it).
      const Eigen::Vector2d r = bearingInnovation(z[i], lamps[j].z);
      const double det = S(0, 0) * S(1, 1) - S(0, 1) * S(1, 0);
      if (!(det > 0.0) || !(S(0, 0) > 0.0)) continue;
      const double m2 = (S(1, 1) * r.x() * r.x() - (S(0, 1) + S(1, 0)) * r.x() * r.y() + S(0, 0) * r.y() * r.y()) / det;
      if (m2 <= count_gate_sq_) near(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = m2;
      if (!(m2 <= gate_bearing_sq_)) continue;
      const double lg = -0.5 * (m2 + std::log(det)) - std::log(2.0 * kPi);
      cost(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = -(log_pd + lg - log_clutter_density_);
    }
  }
  const AssignmentResult a = solveAssignment(cost);
  std::vector<int> lamp_of(z.size(), -1);
  std::vector<char> taken(lamps.size(), 0);
  double l = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < z.size(); ++i) {
    const int j = i < a.col_of_row.size() ? a.col_of_row[i] : -1;
    if (j < 0) continue;
    lamp_of[i] = j, taken[static_cast<std::size_t>(j)] = 1, ++n;
    l -= cost(static_cast<Eigen::Index>(i), j);
  }
  for (std::size_t j = 0; j < lamps.size(); ++j)
    if (lamps[j].expected && !taken[j]) l += log_miss;
  *llr = l;
  *count_llr = countMatches(lamps, z, lamp_of, near);
  *matched = n;
  return lamp_of;
}

double GlobalLocaliser::countMatches(const std::vector<Predicted>& lamps, const std::vector<BearingMeasurement>& z,
                                     const std::vector<int>& lamp_of, const Eigen::MatrixXd& near) const {
  const double log_pd = std::log(perception_.detection_probability);
  const double log_miss = std::log(std::max(1.0 - perception_.detection_probability, 1e-12));
  std::vector<char> taken(lamps.size(), 0);
  std::vector<int> of = lamp_of;
  for (int j : of)
    if (j >= 0) taken[static_cast<std::size_t>(j)] = 1;
  // A bearing the gate left out but within the wider gate of a free lamp is that lamp's (greedy, in
  // bearing order): a pose and its twin must not be told apart by a residual at the gate's edge.
  for (std::size_t i = 0; i < z.size(); ++i) {
    if (of[i] >= 0) continue;
    Eigen::Index best = -1;
    for (Eigen::Index j = 0; j < near.cols(); ++j)
      if (!taken[static_cast<std::size_t>(j)] && near(static_cast<Eigen::Index>(i), j) < kForbiddenCost &&
          (best < 0 || near(static_cast<Eigen::Index>(i), j) < near(static_cast<Eigen::Index>(i), best)))
        best = j;
    if (best >= 0) of[i] = static_cast<int>(best), taken[static_cast<std::size_t>(best)] = 1;
  }
  double c = 0.0;
  for (std::size_t i = 0; i < z.size(); ++i) {
    // Only bearings inside both ranges by their own geometry count: the same for a pose and its
    // twin (their lamps, map errors within the margin, are predicted for both).
    if (of[i] < 0 || !reachesInside(z[i])) continue;
    // The match's worth by its count: E[r^T S^-1 r] = 2, and the bearing's own noise for |S|.
    const Eigen::Matrix2d Q = bearingCovariance(z[i]);
    c += log_pd - 0.5 * (2.0 + std::log(Q.determinant())) - std::log(2.0 * kPi) - log_clutter_density_;
  }
  for (std::size_t j = 0; j < lamps.size(); ++j)
    if (lamps[j].inner && !taken[j]) c += log_miss;
  return c;
}

bool GlobalLocaliser::reachesInside(const BearingMeasurement& m) const {
  for (double h : index_.classHeights()) {
    const auto q = horizontalPointInRobot(m.azimuth_rad, m.elevation_rad, m.p_CinR_m, h, opt_.max_range_m);
    if (!q) continue;
    const double horizontal_m = (*q - m.p_CinR_m.head<2>()).norm(), vertical_m = h - m.p_CinR_m.z();
    if (std::hypot(horizontal_m, vertical_m) <= perception_.max_range_m) return true;
  }
  return false;
}

namespace {

// Gauss-Newton on the matched bearings from x, with an optional prior N(x0, P0): the pose minimising
// sum r^T Q^-1 r (+ (x - x0)^T P0^-1 (x - x0)) and the inverse of its information; false when the
// information is not positive definite.
struct Match {
  Eigen::Vector3d p_W;
  Eigen::Matrix2d R_lamp;  ///< the lamp's covariance in bearing space, added to the bearing's
  const BearingMeasurement* z;
};

bool gaussNewton(const std::vector<Match>& m, const Eigen::Matrix3d* prior_info, const Pose2& x0, Pose2& x,
                 Eigen::Matrix3d& cov) {
  for (int it = 0; it < 4; ++it) {
    Eigen::Matrix3d info = prior_info ? *prior_info : Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    if (prior_info) {
      const Eigen::Vector3d d(x0.x_m - x.x_m, x0.y_m - x.y_m, wrapAngle(x0.theta_rad - x.theta_rad));
      g += *prior_info * d;
    }
    for (const Match& k : m) {
      Eigen::Matrix<double, 2, 3> H;
      const auto zhat = predictBearing(k.p_W, x, k.z->p_CinR_m, &H);
      if (!zhat) return false;
      const Eigen::Matrix2d Qi = (bearingCovariance(*k.z) + k.R_lamp).inverse();
      info += H.transpose() * Qi * H;
      g += H.transpose() * Qi * bearingInnovation(*k.z, *zhat);
    }
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(info);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return false;
    const Eigen::Vector3d dx = ldlt.solve(g);
    if (!dx.allFinite()) return false;
    x = Pose2{x.x_m + dx.x(), x.y_m + dx.y(), wrapAngle(x.theta_rad + dx.z())};
    cov = ldlt.solve(Eigen::Matrix3d::Identity());
    cov = 0.5 * (cov + cov.transpose()).eval();
    if (dx.head<2>().norm() < 1e-7 && std::abs(dx.z()) < 1e-9) break;
  }
  return cov.allFinite();
}

}  // namespace

GlobalLocaliser::Fit GlobalLocaliser::fit(const Pose2& pose_W, const Eigen::Matrix3d& cov, bool prior,
                                          const std::vector<BearingMeasurement>& z) const {
  const Eigen::Vector3d c = cameraOffset(z, perception_);
  Fit f;
  for (const BearingMeasurement& m : z) {
    if (!usable(m)) continue;
    bool reaches = false;
    for (double h : index_.classHeights())
      reaches = reaches ||
                horizontalPointInRobot(m.azimuth_rad, m.elevation_rad, m.p_CinR_m, h, opt_.max_range_m).has_value();
    f.in_range += reaches ? 1 : 0;
  }
  f.pose_W = pose_W, f.cov = cov;
  Eigen::Matrix3d gate_cov = cov;
  const Eigen::Matrix3d prior_info = cov.inverse();
  // A seed (from two bearings) is fitted again while its assignment grows: a seed 0.5 m and 10 deg
  // off matches a few lamps and its fit more (irregular 44, lamps at 4-7 m in one height class: the
  // best seed matched 3-22 of about 42 lamps after two rounds, for 23 frames; 42 in the first frame
  // with the rounds repeated). Round 0 is gated by the seed's own wide covariance, the later rounds
  // by the fit's.
  int matched_before = -1;
  for (int round = 0; round < (prior ? 1 : kMaxSeedFitRounds); ++round) {
    const std::vector<Predicted> lamps = predictVisible(f.pose_W, c);
    const std::vector<int> lamp_of = assign(lamps, gate_cov, z, &f.llr, &f.count_llr, &f.matched);
    // Converged when the assignment stopped growing; its fit below is the last.
    const bool converged = round >= 2 && f.matched <= matched_before;
    matched_before = f.matched;
    f.expected =
        static_cast<int>(std::count_if(lamps.begin(), lamps.end(), [](const Predicted& p) { return p.expected; }));
    std::vector<Match> zs;
    for (std::size_t i = 0; i < z.size(); ++i) {
      if (lamp_of[i] < 0) continue;
      const Predicted& pr = lamps[static_cast<std::size_t>(lamp_of[i])];
      zs.push_back({index_.lamp(pr.lamp), pr.R_lamp, &z[i]});
    }
    if (prior && zs.empty()) {
      f.ok = true;  // nothing matched: the prediction stands
      return f;
    }
    if (!prior && zs.size() < 2) return f;
    Pose2 x = f.pose_W;
    Eigen::Matrix3d P;
    if (!gaussNewton(zs, prior ? &prior_info : nullptr, pose_W, x, P)) return f;
    f.pose_W = x, f.cov = P, gate_cov = P;
    if (converged) break;
  }
  f.ok = true;
  return f;
}

namespace {

// P(X <= k) for X ~ Binomial(n, p), p < 1.
double binomialCdf(int k, int n, double p) {
  if (k < 0) return 0.0;
  if (k >= n) return 1.0;
  double term = std::pow(1.0 - p, n), sum = 0.0;  // P(X = 0)
  for (int i = 0; i <= k; ++i) {
    sum += term;
    term *= (n - i) / (i + 1.0) * p / (1.0 - p);
  }
  return std::min(sum, 1.0);
}

// P(U >= k) for U ~ Poisson(lambda).
double poissonUpperTail(int k, double lambda) {
  if (k <= 0) return 1.0;
  double term = std::exp(-lambda), below = 0.0;
  for (int i = 0; i < k; ++i) {
    below += term;
    term *= lambda / (i + 1.0);
  }
  return std::max(1.0 - below, 0.0);
}

}  // namespace

bool countsExplained(int matched, int expected, int unexplained, double p_d, const GlobalLocalisationOptions& o) {
  const double alpha = 1.0 - o.consistency_probability;
  if (p_d >= 1.0 ? matched < expected : binomialCdf(std::min(matched, expected), expected, p_d) < alpha) return false;
  return poissonUpperTail(unexplained, o.clutter_per_frame) >= alpha;
}

bool GlobalLocaliser::countsConsistent(int matched, int expected, int unexplained) const {
  return countsExplained(matched, expected, unexplained, perception_.detection_probability, opt_);
}

bool GlobalLocaliser::consistent(const Fit& f) const {
  return countsConsistent(f.matched, f.expected, f.in_range - f.matched);
}

}  // namespace omnislam::slam
