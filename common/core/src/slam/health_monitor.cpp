// The filter's health: ESS, innovation consistency, departure from the odometry; see health_monitor.h.
#include "omnislam/core/slam/health_monitor.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "omnislam/core/slam/chi_square.h"
#include "omnislam/core/slam/options_table.h"

namespace omnislam::slam {

namespace {

// A window of steps while standing still never fills with travel; this bounds its memory and the
// cost of compounding it at every step (about 30 us for 1000 steps), the oldest steps leaving first.
constexpr std::size_t kMaxWindowSteps = 1000;

std::string format(const char* fmt, double a, double b = 0.0, double c = 0.0, double d = 0.0) {
  char buf[200];
  std::snprintf(buf, sizeof buf, fmt, a, b, c, d);
  return buf;
}

// d^2 = e^T P^-1 e of the difference of the relative motions S_a^-1 S_t and O_a^-1 O_t.
double departure(const Pose2& slam_a, const Pose2& odom_a, const Pose2& slam_t, const Pose2& odom_t,
                 const Eigen::Matrix3d& P) {
  const Pose2 d_s = slam_a.between(slam_t), d_o = odom_a.between(odom_t);
  const Eigen::Vector3d e(d_s.x_m - d_o.x_m, d_s.y_m - d_o.y_m, wrapAngle(d_s.theta_rad - d_o.theta_rad));
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(P);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || P.isZero(0.0)) return 0.0;
  const double d2 = e.dot(ldlt.solve(e));
  return std::isfinite(d2) ? std::max(d2, 0.0) : 0.0;
}

void putPose(ByteWriter& w, const Pose2& p) {
  w.f64(p.x_m);
  w.f64(p.y_m);
  w.f64(p.theta_rad);
}
Pose2 getPose(ByteReader& r) {  // a braced list is evaluated in order
  return Pose2{r.f64("health pose"), r.f64("health pose"), r.f64("health pose")};
}
void putMatrix(ByteWriter& w, const Eigen::Matrix3d& m) {
  for (int i = 0; i < 9; ++i) w.f64(m(i));
}
Eigen::Matrix3d getMatrix(ByteReader& r) {
  Eigen::Matrix3d m;
  for (int i = 0; i < 9; ++i) m(i) = r.f64("health covariance");
  return m;
}

}  // namespace

std::string HealthOptions::validate() const { return options::checkRanges(*this, options::healthFields()); }

const std::vector<std::string>& healthStateNames() {
  static const std::vector<std::string> n{"ok", "uncertain", "diverged"};
  return n;
}

Eigen::Matrix3d composeCovariance(const Pose2& D, const Eigen::Matrix3d& P, const Pose2& u, const Eigen::Matrix3d& Q) {
  Eigen::Matrix3d J_u;
  predictPose(D, u, &J_u);
  const Eigen::Matrix3d out = propagatePoseCovariance(D, P, u, J_u * Q * J_u.transpose());  // motion_model.h
  return 0.5 * (out + out.transpose());
}

Pose2 fallbackPose(const Pose2& good_slam_W, const Pose2& good_odom_O, const Pose2& odom_O) {
  return good_slam_W.compose(good_odom_O.between(odom_O));
}

HealthMonitor::HealthMonitor(const HealthOptions& options, const MotionNoiseOptions& motion)
    : options_(options), motion_(motion) {
  std::string err = options_.validate();
  if (err.empty() && !(err = motion_.validate()).empty()) err = "motion." + err;
  if (!err.empty()) throw std::invalid_argument("health options: " + err);
  threshold_ = chiSquareQuantile(options_.divergence_probability, 3.0);
}

void HealthMonitor::reset() {
  started_ = false;
  travel_m_ = 0.0;
  window_.clear();
  start_ = good_ = Anchor{};
  nis_.clear();
  exceed_streak_ = clear_streak_ = 0;
  diverged_ = false;
}

void HealthMonitor::advance(const HealthInput& in) {
  if (!started_) {
    started_ = true;
    window_.push_back(Step{in.slam_W, in.odom_O, Pose2{}, Eigen::Matrix3d::Zero(), 0.0});
    start_ = good_ = Anchor{in.slam_W, in.odom_O, in.slam_cov, Eigen::Matrix3d::Zero(), 0.0};
    return;
  }
  const Pose2 u = window_.back().odom_O.between(in.odom_O);
  const Eigen::Matrix3d sigma_u = incrementCovariance(u, motion_);
  travel_m_ += std::hypot(u.x_m, u.y_m);
  for (Anchor* a : {&start_, &good_})
    a->P = composeCovariance(a->odom_O.between(window_.back().odom_O), a->P, u, sigma_u);
  window_.push_back(Step{in.slam_W, in.odom_O, u, sigma_u, travel_m_});
  // The front is the newest step at least window_m of travel back (or the oldest kept).
  while (window_.size() > kMaxWindowSteps ||
         (window_.size() > 2 && travel_m_ - window_[1].travel_m >= options_.window_m))
    window_.pop_front();
}

double HealthMonitor::windowStatistic(double* travel_m) const {
  const Step& a = window_.front();
  const Step& t = window_.back();
  *travel_m = t.travel_m - a.travel_m;
  Pose2 D;
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  for (std::size_t i = 1; i < window_.size(); ++i) {
    P = composeCovariance(D, P, window_[i].u, window_[i].sigma_u);
    D = D.compose(window_[i].u);
  }
  return departure(a.slam_W, a.odom_O, t.slam_W, t.odom_O, P);
}

void HealthMonitor::nisWindow(const HealthInput& in, HealthReport& r) {
  r.nis = in.nis;
  r.nis_dof = in.nis_dof;
  if (in.nis_dof > 0.0 && std::isfinite(in.nis)) {
    nis_.emplace_back(in.nis, in.nis_dof);
    while (static_cast<int>(nis_.size()) > options_.nis_window_frames) nis_.pop_front();
  }
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (const auto& v : nis_) sum += v;
  if (!(sum.y() > 0.0)) return;
  const double n = sum.y(), p = options_.nis_probability;
  r.nis_window_dof = n;
  r.nis_window_per_dof = sum.x() / n;
  r.nis_lower = chiSquareQuantile(0.5 * (1.0 - p), n) / n;
  r.nis_upper = chiSquareQuantile(0.5 * (1.0 + p), n) / n;
}

void HealthMonitor::decide(const HealthInput& in, const Tests& t, HealthReport& r) {
  exceed_streak_ = t.total_exceeds ? exceed_streak_ + 1 : 0;
  clear_streak_ = t.total_exceeds ? 0 : clear_streak_ + 1;
  if (!diverged_ && exceed_streak_ >= options_.divergence_frames) diverged_ = true;
  else if (diverged_ && clear_streak_ >= options_.recovery_frames) diverged_ = false;
  r.exceedances = exceed_streak_;
  const bool ess_bad = in.weights_degenerate || in.ess < options_.ess_min_fraction * in.num_particles;
  if (diverged_) {
    r.state = HealthState::kDiverged;
    r.reason = t.total_exceeds ? format("diverged: departure %.3g > %.3g over %.3g m", r.total_statistic, r.threshold,
                                        r.total_travel_m)
                               : format("diverged: recovering, %.0f of %.0f steps within the odometry's noise",
                                        clear_streak_, options_.recovery_frames);
  } else if (t.total_exceeds) {
    r.state = HealthState::kUncertain;
    r.reason = format("departs from the odometry: %.3g > %.3g (%.0f of %.0f)", r.total_statistic, r.threshold,
                      exceed_streak_, options_.divergence_frames);
  } else if (t.window_exceeds) {
    r.state = HealthState::kUncertain;
    r.reason = format("moves unlike the odometry over the last %.3g m: %.3g > %.3g", r.window_travel_m,
                      r.window_statistic, r.threshold);
  } else if (t.nis_high) {
    r.state = HealthState::kUncertain;
    r.reason = format("innovations too large: NIS/dof %.3g above %.3g", r.nis_window_per_dof, r.nis_upper);
  } else if (ess_bad) {
    r.state = HealthState::kUncertain;
    r.reason = in.weights_degenerate
                   ? std::string("weights degenerate (reset to uniform)")
                   : format("ESS %.3g below %.3g", in.ess, options_.ess_min_fraction * in.num_particles);
  } else {
    r.state = HealthState::kOk;
    r.reason = "ok";
  }
  // The last good step, which the fallback moves on from: no departure, neither since the start nor
  // over the window (a jump not yet beyond the total's noise is not trusted either).
  if (!diverged_ && !t.total_exceeds && !t.window_exceeds)
    good_ = Anchor{in.slam_W, in.odom_O, in.slam_cov, Eigen::Matrix3d::Zero(), travel_m_};
}

HealthReport HealthMonitor::update(const HealthInput& in) {
  HealthReport r;
  advance(in);
  r.threshold = threshold_;
  r.window_statistic = windowStatistic(&r.window_travel_m);
  r.total_statistic = departure(start_.slam_W, start_.odom_O, in.slam_W, in.odom_O, start_.P);
  r.total_travel_m = travel_m_ - start_.travel_m;
  nisWindow(in, r);
  Tests t;
  t.nis_high = r.nis_window_dof > 0.0 && r.nis_window_per_dof > r.nis_upper;
  t.window_exceeds = r.window_statistic > threshold_;
  t.total_exceeds = r.total_statistic > threshold_;
  decide(in, t, r);
  r.pose_W = in.slam_W;
  r.pose_cov = in.slam_cov;
  if (diverged_ && options_.policy == HealthPolicy::kFallbackOdometry) {
    const Pose2 d_o = good_.odom_O.between(in.odom_O);
    r.fallback = true;
    r.pose_W = fallbackPose(good_.slam_W, good_.odom_O, in.odom_O);
    r.pose_cov = composeCovariance(good_.slam_W, good_.slam_cov, d_o, good_.P);
  }
  return r;
}

std::optional<std::pair<Pose2, Eigen::Matrix3d>> HealthMonitor::fallbackAt(const Pose2& odom_O) const {
  if (!diverged_ || options_.policy != HealthPolicy::kFallbackOdometry) return std::nullopt;
  const Pose2 d_o = good_.odom_O.between(odom_O);
  return std::make_pair(fallbackPose(good_.slam_W, good_.odom_O, odom_O),
                        composeCovariance(good_.slam_W, good_.slam_cov, d_o, good_.P));
}

void HealthMonitor::saveState(ByteWriter& w) const {
  w.boolean(started_);
  w.f64(travel_m_);
  w.u64(window_.size());
  for (const Step& s : window_) {
    for (const Pose2& p : {s.slam_W, s.odom_O, s.u}) putPose(w, p);
    putMatrix(w, s.sigma_u);
    w.f64(s.travel_m);
  }
  for (const Anchor* a : {&start_, &good_}) {
    putPose(w, a->slam_W);
    putPose(w, a->odom_O);
    putMatrix(w, a->slam_cov);
    putMatrix(w, a->P);
    w.f64(a->travel_m);
  }
  w.u64(nis_.size());
  for (const auto& v : nis_) {
    w.f64(v.x());
    w.f64(v.y());
  }
  w.i32(exceed_streak_);
  w.i32(clear_streak_);
  w.boolean(diverged_);
}

void HealthMonitor::loadState(ByteReader& r) {
  HealthMonitor m = *this;  // read into a copy: a malformed state leaves this one as it was
  m.started_ = r.boolean("health started");
  m.travel_m_ = r.f64("health travel");
  m.window_.resize(r.count("health window", kMaxWindowSteps, 8 * 19));
  for (Step& s : m.window_) {
    for (Pose2* p : {&s.slam_W, &s.odom_O, &s.u}) *p = getPose(r);
    s.sigma_u = getMatrix(r);
    s.travel_m = r.f64("health travel");
  }
  for (Anchor* a : {&m.start_, &m.good_}) {
    a->slam_W = getPose(r);
    a->odom_O = getPose(r);
    a->slam_cov = getMatrix(r);
    a->P = getMatrix(r);
    a->travel_m = r.f64("health travel");
  }
  m.nis_.resize(r.count("health NIS window", 1'000'000, 16));
  for (auto& v : m.nis_) {
    const double nis = r.f64("health NIS");
    v = Eigen::Vector2d(nis, r.f64("health NIS dof"));
  }
  m.exceed_streak_ = r.i32("health streak");
  m.clear_streak_ = r.i32("health streak");
  m.diverged_ = r.boolean("health diverged");
  if (m.exceed_streak_ < 0 || m.clear_streak_ < 0) throw StateFormatError("health state: negative streak");
  *this = std::move(m);
}

}  // namespace omnislam::slam
