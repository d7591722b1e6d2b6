// One robust solve of the keyframe graph on Ceres (smoother.h): building the problem, solving,
// removing outlying bearings, and the marginal covariances.
#include "omnislam/smoothing/smoother.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <sstream>

#include "omnislam/core/slam/bearing_model.h"
#include "omnislam/core/slam/chi_square.h"
#include "omnislam/smoothing/factors.h"

namespace omnislam::smoothing {
namespace {

bool isPoint(slam::LandmarkKind k) { return k == slam::LandmarkKind::kPoint3D; }

/// The parameter blocks and residual blocks of one solve.
struct Blocks {
  std::vector<std::array<double, 3>> poses, landmarks;
  double ceiling_height_m = 0.0;
  std::array<double, 2> calibration{1.0, 0.0};      ///< odometry scale, heading drift [rad/m]
  std::vector<ceres::ResidualBlockId> bearing_ids;  ///< per Graph::bearings (nullptr once removed)
  std::vector<int> bearings_of_landmark;            ///< count of bearings still in the graph
  std::vector<char> landmark_in_problem;
  std::vector<char> has_prior;  ///< per landmark: 1 with a LandmarkPrior
};

/// The covariance of a bearing as the filter uses it.
Eigen::Matrix2d bearingSigma(const slam::BearingMeasurement& z, bool inflate) {
  const slam::MeasMat S = slam::measurementCovariance(z, inflate);
  Eigen::Matrix2d out = Eigen::Matrix2d::Zero();
  out.topLeftCorner(S.rows(), S.cols()) = S;
  return out;
}

void addBearings(const Graph& g, const SolverOptions& o, ceres::Problem& pb, Blocks& b, ceres::LossFunction* loss) {
  b.bearing_ids.assign(g.bearings.size(), nullptr);
  b.bearings_of_landmark.assign(g.landmarks.size(), 0);
  for (std::size_t i = 0; i < g.bearings.size(); ++i) {
    const BearingEdge& e = g.bearings[i];
    double* pose = b.poses[e.keyframe].data();
    double* lm = b.landmarks[e.landmark].data();
    const Eigen::Matrix2d S = bearingSigma(e.z, o.inflate_azimuth_near_zenith);
    ceres::CostFunction* cost = isPoint(e.z.kind)
                                    ? static_cast<ceres::CostFunction*>(new PointBearingCost(e.z, S))
                                    : static_cast<ceres::CostFunction*>(new LineAzimuthCost(e.z, std::sqrt(S(0, 0))));
    b.bearing_ids[i] = pb.AddResidualBlock(cost, o.bearing_loss_sigmas > 0.0 ? loss : nullptr, pose, lm);
    ++b.bearings_of_landmark[e.landmark];
  }
}

void addCeiling(const Graph& g, ceres::Problem& pb, Blocks& b, ceres::LossFunction* loss) {
  if (std::holds_alternative<NoCeilingPrior>(g.ceiling)) return;
  double height_sum = 0.0;
  int n = 0;
  for (std::size_t j = 0; j < g.landmarks.size(); ++j) {
    if (!isPoint(g.landmarks[j].kind)) continue;
    height_sum += g.landmarks[j].p_LinW_m.z();
    ++n;
  }
  if (n == 0) return;
  b.ceiling_height_m = height_sum / n;  // the flat ceiling's start: the mean landmark height
  for (std::size_t j = 0; j < g.landmarks.size(); ++j) {
    if (!isPoint(g.landmarks[j].kind)) continue;
    if (const auto* known = std::get_if<KnownCeilingHeight>(&g.ceiling)) {
      pb.AddResidualBlock(new KnownHeightCost(known->height_m, known->sigma_m), loss, b.landmarks[j].data());
    } else {
      const auto& flat = std::get<FlatCeiling>(g.ceiling);
      pb.AddResidualBlock(new FlatCeilingCost(flat.sigma_m), loss, b.landmarks[j].data(), &b.ceiling_height_m);
    }
  }
}

void addOdometry(const Graph& g, ceres::Problem& pb, Blocks& b) {
  if (!g.odometry_calibration) {
    for (const auto& e : g.odometry)
      pb.AddResidualBlock(new OdometryCost(e.u_AtoB, e.Sigma_u), nullptr, b.poses[e.from].data(), b.poses[e.to].data());
    return;
  }
  const OdometryCalibrationPrior& c = *g.odometry_calibration;
  pb.AddResidualBlock(new CalibrationPriorCost(c.scale_sigma, c.drift_sigma_rad_per_m), nullptr, b.calibration.data());
  for (const auto& e : g.odometry)
    pb.AddResidualBlock(new CalibratedOdometryCost(e.u_AtoB, e.Sigma_u), nullptr, b.poses[e.from].data(),
                        b.poses[e.to].data(), b.calibration.data());
}

/// Landmark priors, never down-weighted; a landmark with one counts as located (see dropUnderdetermined).
void addLandmarkPriors(const Graph& g, ceres::Problem& pb, Blocks& b) {
  b.has_prior.assign(g.landmarks.size(), 0);
  for (const auto& p : g.landmark_priors) {
    double* lm = b.landmarks[p.landmark].data();
    ceres::CostFunction* cost =
        isPoint(g.landmarks[p.landmark].kind)
            ? static_cast<ceres::CostFunction*>(new LandmarkPriorCost<3>(p.mean_m, p.information))
            : static_cast<ceres::CostFunction*>(
                  new LandmarkPriorCost<2>(p.mean_m.head<2>(), p.information.topLeftCorner<2, 2>()));
    pb.AddResidualBlock(cost, nullptr, lm);
    b.has_prior[p.landmark] = 1;
  }
}

/// Adds every block of the graph; the loss functions are owned by the caller.
void buildProblem(const Graph& g, const SolverOptions& o, ceres::Problem& pb, Blocks& b,
                  ceres::LossFunction* bearing_loss, ceres::LossFunction* ceiling_loss) {
  for (const auto& k : g.keyframes) b.poses.push_back({k.T_WtoR.x_m, k.T_WtoR.y_m, k.T_WtoR.theta_rad});
  for (const auto& l : g.landmarks) b.landmarks.push_back({l.p_LinW_m.x(), l.p_LinW_m.y(), l.p_LinW_m.z()});
  for (std::size_t k = 0; k < b.poses.size(); ++k) pb.AddParameterBlock(b.poses[k].data(), 3);
  for (std::size_t j = 0; j < b.landmarks.size(); ++j)
    pb.AddParameterBlock(b.landmarks[j].data(), isPoint(g.landmarks[j].kind) ? 3 : 2);
  for (const auto& p : g.pose_priors)
    pb.AddResidualBlock(new PosePriorCost(p.mean, p.Sigma), nullptr, b.poses[p.keyframe].data());
  addOdometry(g, pb, b);
  addBearings(g, o, pb, b, bearing_loss);
  addCeiling(g, pb, b, ceiling_loss);
  addLandmarkPriors(g, pb, b);
  b.landmark_in_problem.assign(g.landmarks.size(), 1);
}

/// A landmark left with fewer bearings than it needs to be located leaves the problem (with its
/// other factors), keeping its initial value: points need two rays, lines two azimuths. A landmark
/// with a prior stays: the prior is the caller's word that it is located with what it has.
void dropUnderdetermined(const Graph& g, ceres::Problem& pb, Blocks& b) {
  for (std::size_t j = 0; j < g.landmarks.size(); ++j) {
    if (!b.landmark_in_problem[j] || b.bearings_of_landmark[j] >= 2 || b.has_prior[j]) continue;
    for (std::size_t i = 0; i < g.bearings.size(); ++i) {
      if (g.bearings[i].landmark != static_cast<int>(j) || !b.bearing_ids[i]) continue;
      pb.RemoveResidualBlock(b.bearing_ids[i]);
      b.bearing_ids[i] = nullptr;
    }
    pb.RemoveParameterBlock(b.landmarks[j].data());  // removes its ceiling factor too
    b.landmark_in_problem[j] = 0;
  }
}

/// Removes the bearings over the gate; returns how many.
int removeOutliers(const Graph& g, const SolverOptions& o, ceres::Problem& pb, Blocks& b, Solution& s) {
  const double gate[3] = {0.0, slam::chiSquareQuantile(1.0 - o.outlier_probability, 1.0),
                          slam::chiSquareQuantile(1.0 - o.outlier_probability, 2.0)};
  int removed = 0;
  for (std::size_t i = 0; i < g.bearings.size(); ++i) {
    if (!b.bearing_ids[i]) continue;
    double cost = 0.0;
    if (!pb.EvaluateResidualBlock(b.bearing_ids[i], false, &cost, nullptr, nullptr)) continue;
    const double chi2 = 2.0 * cost;
    if (chi2 <= gate[slam::measurementDim(g.bearings[i].z.kind)]) continue;
    const BearingEdge& e = g.bearings[i];
    s.removed.push_back({static_cast<int>(i), g.keyframes[e.keyframe].id, g.landmarks[e.landmark].id, chi2});
    pb.RemoveResidualBlock(b.bearing_ids[i]);
    b.bearing_ids[i] = nullptr;
    --b.bearings_of_landmark[e.landmark];
    ++removed;
  }
  return removed;
}

bool runSolver(const SolverOptions& o, ceres::Problem& pb, Blocks& b, Solution& s) {
  ceres::Solver::Options so;
  constexpr ceres::LinearSolverType kType[] = {ceres::SPARSE_NORMAL_CHOLESKY, ceres::SPARSE_SCHUR, ceres::DENSE_SCHUR};
  so.linear_solver_type = kType[static_cast<int>(o.linear_solver)];
  // Eigen's sparse Cholesky: no OpenMP or BLAS threads behind Ceres' back (SuiteSparse's spin).
  so.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
  so.max_num_iterations = o.max_iterations;
  so.function_tolerance = o.function_tolerance;
  so.num_threads = 1;  // deterministic
  so.logging_type = ceres::SILENT;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (std::size_t j = 0; j < b.landmarks.size(); ++j)
    if (b.landmark_in_problem[j]) ordering->AddElementToGroup(b.landmarks[j].data(), 0);
  for (auto& p : b.poses) ordering->AddElementToGroup(p.data(), 1);
  if (pb.HasParameterBlock(&b.ceiling_height_m)) ordering->AddElementToGroup(&b.ceiling_height_m, 1);
  if (pb.HasParameterBlock(b.calibration.data())) ordering->AddElementToGroup(b.calibration.data(), 1);
  if (o.linear_solver != LinearSolver::kSparseNormalCholesky) so.linear_solver_ordering = ordering;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &pb, &summary);
  if (s.solves == 0) s.initial_cost = summary.initial_cost;
  s.final_cost = summary.final_cost;
  s.iterations += static_cast<int>(summary.iterations.size());
  ++s.solves;
  if (summary.termination_type == ceres::FAILURE || !std::isfinite(summary.final_cost)) {
    s.failure = "the solver failed: " + summary.message;
    return false;
  }
  return true;
}

}  // namespace

namespace {

void computeCovariances(const Graph& g, ceres::Problem& pb, Blocks& b, Solution& s) {
  ceres::Covariance::Options co;
  co.num_threads = 1;
  co.algorithm_type = ceres::SPARSE_QR;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> wanted;
  for (std::size_t j = 0; j < b.landmarks.size(); ++j)
    if (b.landmark_in_problem[j]) wanted.emplace_back(b.landmarks[j].data(), b.landmarks[j].data());
  const double* last = b.poses.back().data();
  wanted.emplace_back(last, last);
  if (!cov.Compute(wanted, &pb)) {
    s.covariance_failure = "the information matrix at the solution is rank deficient";
    return;
  }
  s.landmark_cov_m2.assign(g.landmarks.size(), Eigen::Matrix3d::Zero());
  for (std::size_t j = 0; j < b.landmarks.size(); ++j) {
    if (!b.landmark_in_problem[j]) continue;
    if (isPoint(g.landmarks[j].kind)) {
      Eigen::Matrix<double, 3, 3, Eigen::RowMajor> C;
      cov.GetCovarianceBlock(b.landmarks[j].data(), b.landmarks[j].data(), C.data());
      s.landmark_cov_m2[j] = C;
    } else {
      Eigen::Matrix<double, 2, 2, Eigen::RowMajor> C;
      cov.GetCovarianceBlock(b.landmarks[j].data(), b.landmarks[j].data(), C.data());
      s.landmark_cov_m2[j].topLeftCorner<2, 2>() = C;
    }
  }
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> P;
  cov.GetCovarianceBlock(last, last, P.data());
  s.last_pose_cov = P;
}

/// kGivenPoses: per landmark, the inverse of the information of its bearings still in the graph at
/// the solution (plain least squares: the loss's weights are not applied).
void covariancesGivenPoses(const Graph& g, const SolverOptions& o, Solution& s) {
  std::vector<Eigen::Matrix3d> info(g.landmarks.size(), Eigen::Matrix3d::Zero());
  for (std::size_t i = 0; i < g.bearings.size(); ++i) {
    if (!s.bearing_used[i]) continue;
    const BearingEdge& e = g.bearings[i];
    const Pose2& x = s.keyframe_poses[e.keyframe];
    const Eigen::Matrix2d W =
        whitener<2>(bearingSigma(e.z, o.inflate_azimuth_near_zenith)).value_or(Eigen::Matrix2d::Zero());
    if (isPoint(e.z.kind)) {
      Eigen::Matrix<double, 2, 3> Jl;
      if (!pointBearingError(e.z, x, s.landmarks_m[e.landmark], nullptr, &Jl)) continue;
      const Eigen::Matrix<double, 2, 3> A = W * Jl;
      info[e.landmark] += A.transpose() * A;
    } else {
      Eigen::Matrix<double, 1, 2> Jl;
      if (!lineAzimuthError(e.z, x, s.landmarks_m[e.landmark].head<2>(), nullptr, &Jl)) continue;
      const Eigen::Matrix<double, 1, 2> A = W(0, 0) * Jl;
      info[e.landmark].topLeftCorner<2, 2>() += A.transpose() * A;
    }
  }
  s.landmark_cov_m2.assign(g.landmarks.size(), Eigen::Matrix3d::Zero());
  for (std::size_t j = 0; j < g.landmarks.size(); ++j) {
    const int n = isPoint(g.landmarks[j].kind) ? 3 : 2;
    const Eigen::MatrixXd I = info[j].topLeftCorner(n, n);
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(I);
    if (I.isZero(0.0) || ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
        ldlt.vectorD().minCoeff() <= 1e-12 * I.trace())
      continue;
    s.landmark_cov_m2[j].topLeftCorner(n, n) = ldlt.solve(Eigen::MatrixXd::Identity(n, n));
  }
}

void readSolution(const Graph& g, const Blocks& b, Solution& s) {
  for (const auto& p : b.poses) s.keyframe_poses.push_back(Pose2::fromVec(Eigen::Vector3d(p[0], p[1], p[2])));
  for (std::size_t j = 0; j < b.landmarks.size(); ++j) {
    const auto& l = b.landmarks[j];
    s.landmarks_m.emplace_back(l[0], l[1], isPoint(g.landmarks[j].kind) ? l[2] : g.landmarks[j].p_LinW_m.z());
  }
  s.bearing_used.assign(g.bearings.size(), 0);
  for (std::size_t i = 0; i < g.bearings.size(); ++i) s.bearing_used[i] = b.bearing_ids[i] != nullptr;
  if (std::holds_alternative<FlatCeiling>(g.ceiling)) s.ceiling_height_m = b.ceiling_height_m;
  if (g.odometry_calibration) s.odometry_calibration = Eigen::Vector2d(b.calibration[0], b.calibration[1]);
}

std::string positiveDefinite(const Eigen::Matrix3d& S) { return whitener<3>(S) ? "" : "not positive definite"; }

std::string validateLandmarkPriors(const Graph& g) {
  const int L = static_cast<int>(g.landmarks.size());
  for (std::size_t i = 0; i < g.landmark_priors.size(); ++i) {
    const auto& p = g.landmark_priors[i];
    const std::string who = "landmark prior " + std::to_string(i) + ": ";
    if (p.landmark < 0 || p.landmark >= L) return who + "index";
    if (!p.mean_m.allFinite() || !p.information.allFinite()) return who + "not finite";
    const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(p.information).eigenvalues();
    if (!p.information.isApprox(p.information.transpose(), 1e-9) || ev(0) < -1e-9 * std::max(1.0, std::abs(ev(2))))
      return who + "information not symmetric positive semi-definite";
  }
  return "";
}

std::string validateEdges(const Graph& g) {
  const int K = static_cast<int>(g.keyframes.size()), L = static_cast<int>(g.landmarks.size());
  auto bad = [](const char* what, std::size_t i, const std::string& why) {
    std::ostringstream os;
    os << what << " " << i << ": " << why;
    return os.str();
  };
  for (std::size_t i = 0; i < g.odometry.size(); ++i) {
    const auto& e = g.odometry[i];
    if (e.from < 0 || e.from >= K || e.to < 0 || e.to >= K || e.from == e.to) return bad("odometry", i, "index");
    if (!e.u_AtoB.vec().allFinite()) return bad("odometry", i, "increment not finite");
    if (const auto why = positiveDefinite(e.Sigma_u); !why.empty()) return bad("odometry", i, "Sigma_u " + why);
  }
  for (std::size_t i = 0; i < g.bearings.size(); ++i) {
    const auto& e = g.bearings[i];
    if (e.keyframe < 0 || e.keyframe >= K || e.landmark < 0 || e.landmark >= L) return bad("bearing", i, "index");
    if (e.z.kind != g.landmarks[e.landmark].kind) return bad("bearing", i, "kind differs from its landmark's");
    if (!std::isfinite(e.z.azimuth_rad) || !std::isfinite(e.z.elevation_rad) || !e.z.p_CinR_m.allFinite())
      return bad("bearing", i, "not finite");
    // Inflation only raises the azimuth variance: the raw covariance being PD is enough.
    if (isPoint(e.z.kind) && !whitener<2>(Eigen::Matrix2d(e.z.cov_rad2))) return bad("bearing", i, "covariance not PD");
    if (!isPoint(e.z.kind) && !(e.z.cov_rad2(0, 0) > 0.0)) return bad("bearing", i, "variance not positive");
  }
  for (std::size_t i = 0; i < g.pose_priors.size(); ++i) {
    const auto& p = g.pose_priors[i];
    if (p.keyframe < 0 || p.keyframe >= K) return bad("pose prior", i, "index");
    if (!p.mean.vec().allFinite()) return bad("pose prior", i, "mean not finite");
    if (const auto why = positiveDefinite(p.Sigma); !why.empty()) return bad("pose prior", i, "Sigma " + why);
  }
  return validateLandmarkPriors(g);
}

std::string validateCeiling(const CeilingPrior& c) {
  if (const auto* k = std::get_if<KnownCeilingHeight>(&c)) {
    if (!std::isfinite(k->height_m)) return "ceiling: known height not finite";
    if (!(k->sigma_m > 0.0) || !std::isfinite(k->sigma_m)) return "ceiling: sigma_m must be > 0";
  }
  if (const auto* f = std::get_if<FlatCeiling>(&c))
    if (!(f->sigma_m > 0.0) || !std::isfinite(f->sigma_m)) return "ceiling: sigma_m must be > 0";
  return "";
}

}  // namespace

std::string Graph::validate() const {
  if (keyframes.empty()) return "graph: no keyframe";
  if (pose_priors.empty()) return "graph: no pose prior (the gauge)";
  for (std::size_t k = 0; k < keyframes.size(); ++k)
    if (!keyframes[k].T_WtoR.vec().allFinite()) return "keyframe " + std::to_string(k) + ": pose not finite";
  for (std::size_t j = 0; j < landmarks.size(); ++j)
    if (!landmarks[j].p_LinW_m.allFinite()) return "landmark " + std::to_string(j) + ": position not finite";
  if (auto why = validateEdges(*this); !why.empty()) return why;
  if (odometry_calibration &&
      !(odometry_calibration->scale_sigma > 0.0 && odometry_calibration->drift_sigma_rad_per_m > 0.0 &&
        std::isfinite(odometry_calibration->scale_sigma + odometry_calibration->drift_sigma_rad_per_m)))
    return "odometry calibration: sigmas must be > 0";
  return validateCeiling(ceiling);
}

std::string SolverOptions::validate() const {
  if (max_iterations < 1) return "max_iterations must be >= 1";
  if (!(bearing_loss_sigmas >= 0.0) || !std::isfinite(bearing_loss_sigmas)) return "bearing_loss_sigmas must be >= 0";
  if (!(ceiling_loss_sigmas > 0.0) || !std::isfinite(ceiling_loss_sigmas)) return "ceiling_loss_sigmas must be > 0";
  if (!(outlier_probability > 0.0 && outlier_probability < 0.5)) return "outlier_probability must be in (0, 0.5)";
  if (outlier_rounds < 0) return "outlier_rounds must be >= 0";
  if (!(function_tolerance > 0.0 && function_tolerance < 1.0)) return "function_tolerance must be in (0, 1)";
  return "";
}

Solution solve(const Graph& g, const SolverOptions& o) {
  Solution s;
  s.failure = o.validate();
  if (s.failure.empty()) s.failure = g.validate();
  if (!s.failure.empty()) return s;
  ceres::Problem::Options po;
  po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem pb(po);
  ceres::CauchyLoss bearing_loss(o.bearing_loss_sigmas), ceiling_loss(o.ceiling_loss_sigmas);
  Blocks b;
  buildProblem(g, o, pb, b, &bearing_loss, &ceiling_loss);
  dropUnderdetermined(g, pb, b);
  if (!runSolver(o, pb, b, s)) return s;
  for (int round = 0; round < o.outlier_rounds; ++round) {
    if (removeOutliers(g, o, pb, b, s) == 0) break;
    dropUnderdetermined(g, pb, b);
    if (!runSolver(o, pb, b, s)) return s;
  }
  readSolution(g, b, s);
  if (o.covariances == LandmarkCovariance::kMarginal) computeCovariances(g, pb, b, s);
  if (o.covariances == LandmarkCovariance::kGivenPoses) covariancesGivenPoses(g, o, s);
  s.ok = true;
  return s;
}

}  // namespace omnislam::smoothing
