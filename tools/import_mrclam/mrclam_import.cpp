// One MRCLAM robot -> omnislam log events: see mrclam_import.h.
#include "mrclam_import.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "omnislam/core/angles.h"
#include "omnislam/core/pose2.h"
#include "omnislam/feature_labels_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/validate.h"
#include "omnislam/map_t.hpp"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"

namespace omnislam::mrclam {
namespace {

static_assert(lcmio::Limits{}.max_features == kMaxMeasurementsPerTime, "a frame's size: mrclam_files.h");

constexpr int kFirstLandmarkSubject = 6;  // Barcodes.dat: subjects 1-5 are robots, 6-20 landmarks
constexpr int kRankMap = 0, kRankTruth = 1, kRankOdometry = 2, kRankFeatures = 3, kRankLabels = 4;

template <class Msg>
void add(ImportedLog& log, int64_t utime, int rank, const char* channel, const Msg& m) {
  if (auto why = lcmio::validate(m))
    throw std::logic_error(std::string("importer built an invalid ") + channel + " message: " + *why);
  LogEventOut e;
  e.utime = utime;
  e.rank = rank;
  e.channel = channel;
  e.data.resize(static_cast<size_t>(m.getEncodedSize()));
  m.encode(e.data.data(), 0, static_cast<int>(e.data.size()));
  log.events.push_back(std::move(e));
}

std::string file(const std::string& dir, const std::string& name) {
  return dir.empty() || dir.back() == '/' ? dir + name : dir + "/" + name;
}

}  // namespace

std::string ImportOptions::validate() const {
  if (robot < 1 || robot > 99) return "robot must be in 1..99, got " + std::to_string(robot);
  if (!(bearing_sigma_rad > 0.0) || !(bearing_sigma_rad < 1.0))
    return "bearing sigma must be in (0, 1) rad, got " + std::to_string(bearing_sigma_rad);
  for (double c : camera_position_m)
    if (!std::isfinite(c) || std::abs(c) > 10.0) return "camera position must be finite, within 10 m";
  if (!std::isfinite(max_duration_s)) return "max duration must be finite";
  if (!(max_odometry_gap_s > 0.0)) return "max odometry gap must be > 0";
  return "";
}

std::optional<PoseSample> interpolatePose(const std::vector<PoseSample>& truth, double t) {
  const auto it =
      std::lower_bound(truth.begin(), truth.end(), t, [](const PoseSample& p, double u) { return p.t_s < u; });
  if (it == truth.end()) return std::nullopt;
  if (it->t_s == t) return *it;
  if (it == truth.begin()) return std::nullopt;
  const PoseSample& a = *(it - 1);
  const PoseSample& b = *it;
  const double s = (t - a.t_s) / (b.t_s - a.t_s);
  return PoseSample{t, a.x_m + s * (b.x_m - a.x_m), a.y_m + s * (b.y_m - a.y_m),
                    wrapAngle(a.theta_rad + s * wrapAngle(b.theta_rad - a.theta_rad))};
}

std::vector<PoseSample> integrateOdometry(const std::vector<OdometrySample>& s) {
  std::vector<PoseSample> out;
  if (s.empty()) return out;
  double x = 0.0, y = 0.0, th = 0.0;
  out.push_back({s[0].t_s, 0.0, 0.0, 0.0});
  for (size_t i = 0; i + 1 < s.size(); ++i) {
    const double dt = s[i + 1].t_s - s[i].t_s, v = s[i].v_mps, w = s[i].omega_radps;
    const double dth = w * dt;
    if (std::abs(dth) < 1e-9) {  // straight (the arc's limit)
      x += v * dt * std::cos(th + 0.5 * dth);
      y += v * dt * std::sin(th + 0.5 * dth);
    } else {  // exact arc of radius v / w
      x += v / w * (std::sin(th + dth) - std::sin(th));
      y -= v / w * (std::cos(th + dth) - std::cos(th));
    }
    th += dth;
    out.push_back({s[i + 1].t_s, x, y, wrapAngle(th)});
  }
  return out;
}

namespace {

// Leaves out the rows after max_duration_s from the first odometry sample (counted).
void cutToStretch(const ImportOptions& o, std::vector<OdometrySample>& odo, std::vector<Measurement>& meas,
                  std::vector<PoseSample>& truth, ImportReport& r) {
  r.t0_s = odo.front().t_s;
  if (o.max_duration_s > 0.0) {
    const double t1 = r.t0_s + o.max_duration_s;
    auto cut = [&](auto& v) {
      const size_t before = v.size();
      v.erase(std::remove_if(v.begin(), v.end(), [&](const auto& s) { return s.t_s > t1; }), v.end());
      r.outside_stretch += static_cast<int64_t>(before - v.size());
    };
    cut(odo);
    cut(meas);
    cut(truth);
  }
  r.t_end_s = odo.back().t_s;
}

// The cumulative odometry poses: the wheels' integrated, or (diagnostic) the truth relative to its
// pose at the first odometry sample.
std::vector<PoseSample> odometryPoses(const ImportOptions& o, const std::vector<OdometrySample>& odo,
                                      const std::vector<PoseSample>& truth) {
  auto poses = integrateOdometry(odo);
  if (!o.odometry_from_truth) return poses;
  const auto first = interpolatePose(truth, odo.front().t_s);
  if (!first) throw std::invalid_argument("--odometry-from-truth: no truth at the first odometry sample");
  const Pose2 T0{first->x_m, first->y_m, first->theta_rad};
  for (size_t i = 0; i < odo.size(); ++i) {
    const auto p = interpolatePose(truth, odo[i].t_s);
    const Pose2 rel = p ? T0.between(Pose2{p->x_m, p->y_m, p->theta_rad}) : Pose2{};
    if (p) poses[i] = {odo[i].t_s, rel.x_m, rel.y_m, rel.theta_rad};
    else if (i > 0) poses[i] = {odo[i].t_s, poses[i - 1].x_m, poses[i - 1].y_m, poses[i - 1].theta_rad};
  }
  return poses;
}

void addOdometry(const ImportOptions& o, const std::vector<OdometrySample>& odo, const std::vector<PoseSample>& poses,
                 ImportedLog& log) {
  ImportReport& r = log.report;
  for (size_t i = 0; i < odo.size(); ++i) {
    odometry_t m{};
    m.utime = toUtime(odo[i].t_s);
    m.seq = static_cast<int64_t>(i);
    m.x_m = poses[i].x_m;
    m.y_m = poses[i].y_m;
    m.theta_rad = poses[i].theta_rad;
    m.v_mps = odo[i].v_mps;
    m.omega_radps = odo[i].omega_radps;
    add(log, m.utime, kRankOdometry, channels::kOdometry, m);
    if (i > 0) {
      const double gap = odo[i].t_s - odo[i - 1].t_s;
      r.odometry_max_gap_s = std::max(r.odometry_max_gap_s, gap);
      if (gap > o.max_odometry_gap_s) ++r.odometry_gaps;
      r.odometry_path_m += std::hypot(poses[i].x_m - poses[i - 1].x_m, poses[i].y_m - poses[i - 1].y_m);
    }
  }
  r.odometry_messages = static_cast<int64_t>(odo.size());
}

void addTruthPoses(const std::vector<PoseSample>& truth, ImportedLog& log) {
  for (size_t i = 0; i < truth.size(); ++i) {
    pose_t m{};
    m.utime = toUtime(truth[i].t_s);
    m.seq = static_cast<int64_t>(i);
    m.x_m = truth[i].x_m;
    m.y_m = truth[i].y_m;
    m.theta_rad = wrapAngle(truth[i].theta_rad);
    m.input_seq = -1;
    add(log, m.utime, kRankTruth, channels::kGroundTruthPose, m);
  }
  log.report.truth_poses = static_cast<int64_t>(truth.size());
}

// GROUND_TRUTH_MAP, at the first event.
void addTruthMap(const std::vector<LandmarkTruth>& landmarks, int64_t first_utime, ImportedLog& log) {
  map_t m{};
  m.utime = first_utime;
  m.seq = 0;
  m.input_seq = -1;
  for (const auto& l : landmarks) {
    landmark_t lt{};
    lt.id = l.subject;
    lt.position_m[0] = l.x_m;
    lt.position_m[1] = l.y_m;
    lt.position_m[2] = 0.0;
    lt.kind = feature_t::KIND_VERTICAL_LINE;
    m.landmarks.push_back(lt);
  }
  m.num_landmarks = static_cast<int32_t>(m.landmarks.size());
  m.num_candidates = 0;
  add(log, first_utime, kRankMap, channels::kGroundTruthMap, m);
}

// Who a sighting's barcode belongs to.
struct Subjects {
  std::map<int, int> subject_of_code;
  std::set<int> landmark_subjects;
  std::set<int> unknown_codes;  ///< codes seen that name no landmark, robot or known subject
};

// The label of one sighting (counted in r); nullopt when it is to be dropped (a robot sighting with
// drop_robot_sightings).
std::optional<int64_t> labelSighting(const Measurement& z, const ImportOptions& o, Subjects& subj, ImportReport& r) {
  const auto it = subj.subject_of_code.find(z.code);
  const int subject = it == subj.subject_of_code.end() ? 0 : it->second;  // 0: no subject has this code
  if (it == subj.subject_of_code.end()) {
    ++r.unknown_code_sightings;
    subj.unknown_codes.insert(z.code);
  } else if (subj.landmark_subjects.count(subject)) {
    ++r.landmark_sightings;
    return subject;
  } else if (subject == o.robot) {
    ++r.own_code_sightings;
  } else if (subject < kFirstLandmarkSubject) {
    ++r.robot_sightings;
    if (!o.drop_robot_sightings) return feature_labels_t::OTHER_ROBOT;
    ++r.robot_sightings_dropped;
    return std::nullopt;
  } else {  // a subject >= 6 without a landmark truth line: unknown clutter
    ++r.unknown_code_sightings;
    subj.unknown_codes.insert(z.code);
  }
  return feature_labels_t::UNKNOWN;
}

// One frame of the sightings meas[i, j) (one time): features and their labels.
void frameOf(const std::vector<Measurement>& meas, size_t i, size_t j, const ImportOptions& o, Subjects& subj,
             features_t& f, feature_labels_t& lab, ImportReport& r) {
  f.utime = lab.utime = toUtime(meas[i].t_s);
  f.image_seq = -1;
  f.detector = "mrclam_bearings";
  for (int k = 0; k < 3; ++k) f.camera_position_m[k] = o.camera_position_m[static_cast<size_t>(k)];
  for (size_t k = i; k < j; ++k) {
    const Measurement& z = meas[k];
    const std::optional<int64_t> label = labelSighting(z, o, subj, r);
    if (!label) continue;
    feature_t ft{};
    ft.kind = feature_t::KIND_VERTICAL_LINE;
    ft.azimuth_rad = wrapAngle(z.bearing_rad);
    ft.elevation_rad = 0.0;
    ft.has_elevation = false;
    ft.covariance[0][0] = o.bearing_sigma_rad * o.bearing_sigma_rad;
    r.max_abs_bearing_rad = std::max(r.max_abs_bearing_rad, std::abs(ft.azimuth_rad));
    f.features.push_back(ft);
    lab.landmark_id.push_back(*label);
    lab.source_code.push_back(z.code);
  }
}

// Diagnostic --skip-still-frames: true when the robot moved less than still_frame_m and
// still_frame_rad since the last frame kept.
bool stillFrame(const ImportOptions& o, const std::vector<PoseSample>& poses, int64_t utime,
                std::optional<PoseSample>& last_kept) {
  if (!(o.still_frame_m > 0.0 || o.still_frame_rad > 0.0)) return false;
  const auto p = interpolatePose(poses, static_cast<double>(utime) * 1e-6);
  if (p && last_kept) {
    const bool still = std::hypot(p->x_m - last_kept->x_m, p->y_m - last_kept->y_m) < o.still_frame_m &&
                       std::abs(wrapAngle(p->theta_rad - last_kept->theta_rad)) < o.still_frame_rad;
    if (still) return true;
  }
  if (p) last_kept = p;
  return false;
}

// OMNI_FEATURES + GROUND_TRUTH_FEATURE_LABELS: one frame per distinct time.
void addFrames(const ImportOptions& o, const std::vector<Measurement>& meas, const std::vector<PoseSample>& poses,
               int64_t first_odometry_utime, Subjects& subj, ImportedLog& log) {
  ImportReport& r = log.report;
  r.measurements = static_cast<int64_t>(meas.size());
  int64_t seq = 0;
  std::optional<PoseSample> last_kept;
  for (size_t i = 0; i < meas.size();) {
    size_t j = i;
    while (j < meas.size() && meas[j].t_s == meas[i].t_s) ++j;
    features_t f{};
    feature_labels_t lab{};
    frameOf(meas, i, j, o, subj, f, lab, r);
    i = j;
    if (f.features.empty()) continue;  // only dropped robot sightings (counted above)
    if (stillFrame(o, poses, f.utime, last_kept)) {
      ++r.frames_still_skipped;
      continue;
    }
    f.seq = lab.features_seq = lab.seq = seq++;
    f.num_features = lab.num_features = static_cast<int32_t>(f.features.size());
    r.features += f.num_features;
    r.max_features_per_frame = std::max<int64_t>(r.max_features_per_frame, f.num_features);
    if (f.utime < first_odometry_utime) ++r.frames_before_odometry;
    add(log, f.utime, kRankFeatures, channels::kOmniFeatures, f);
    add(log, lab.utime, kRankLabels, channels::kGroundTruthFeatureLabels, lab);
  }
  r.frames = seq;
}

// The start pose: the truth at the first frame the SLAM process will process (odometry samples
// around it at most max_odometry_gap_s apart: docs/user/slam-process.md, pairing rule 5).
void findStartPose(const ImportOptions& o, const std::vector<OdometrySample>& odo, const std::vector<PoseSample>& truth,
                   ImportedLog& log) {
  for (const auto& e : log.events) {
    if (e.channel != channels::kOmniFeatures) continue;
    const double t = static_cast<double>(e.utime) * 1e-6;
    const auto it = std::lower_bound(odo.begin(), odo.end(), e.utime,
                                     [](const OdometrySample& s, int64_t u) { return toUtime(s.t_s) < u; });
    if (it == odo.end()) break;
    if (toUtime(it->t_s) != e.utime && (it == odo.begin() || it->t_s - (it - 1)->t_s > o.max_odometry_gap_s)) continue;
    log.report.start_pose = interpolatePose(truth, t);
    log.report.start_frame_utime = e.utime;
    break;
  }
}

}  // namespace

ImportedLog importRobot(const std::string& dir, const ImportOptions& o) {
  if (const std::string e = o.validate(); !e.empty()) throw std::invalid_argument(e);
  ImportedLog log;
  ImportReport& r = log.report;
  const std::string n = std::to_string(o.robot);
  auto odo = readOdometry(file(dir, "Robot" + n + "_Odometry.dat"), o.duplicate_times, &r.odometry_file);
  auto meas = readMeasurements(file(dir, "Robot" + n + "_Measurement.dat"), &r.measurement_file);
  auto truth = readGroundtruth(file(dir, "Robot" + n + "_Groundtruth.dat"), o.duplicate_times, &r.groundtruth_file);
  const auto landmarks = readLandmarks(file(dir, "Landmark_Groundtruth.dat"), &r.landmark_file);
  const auto barcodes = readBarcodes(file(dir, "Barcodes.dat"), &r.barcode_file);
  Subjects subj;
  for (const auto& b : barcodes) subj.subject_of_code[b.barcode] = b.subject;
  for (const auto& l : landmarks) subj.landmark_subjects.insert(l.subject);

  cutToStretch(o, odo, meas, truth, r);
  const std::vector<PoseSample> poses = odometryPoses(o, odo, truth);
  addOdometry(o, odo, poses, log);
  addTruthPoses(truth, log);
  int64_t first = toUtime(odo.front().t_s);
  if (!truth.empty()) first = std::min(first, toUtime(truth.front().t_s));
  if (!meas.empty()) first = std::min(first, toUtime(meas.front().t_s));
  addTruthMap(landmarks, first, log);
  addFrames(o, meas, poses, toUtime(odo.front().t_s), subj, log);
  r.unknown_codes.assign(subj.unknown_codes.begin(), subj.unknown_codes.end());
  findStartPose(o, odo, truth, log);

  std::stable_sort(log.events.begin(), log.events.end(), [](const LogEventOut& a, const LogEventOut& b) {
    return a.utime != b.utime ? a.utime < b.utime : a.rank < b.rank;
  });
  return log;
}

std::string ImportReport::describe() const {
  std::ostringstream s;
  s.precision(6);
  for (const FileStats* f : {&odometry_file, &measurement_file, &groundtruth_file, &landmark_file, &barcode_file})
    s << "  " << mrclam::describe(*f) << "\n";
  s << "  imported " << std::fixed << t0_s << " .. " << t_end_s << " s (" << (t_end_s - t0_s) << " s)";
  s.unsetf(std::ios::floatfield);
  if (outside_stretch > 0) s << "; " << outside_stretch << " rows after the stretch left out (--max-duration)";
  s << "\n  ODOMETRY: " << odometry_messages << " messages, path " << odometry_path_m << " m, largest interval "
    << odometry_max_gap_s << " s, " << odometry_gaps << " intervals above the pairing gap\n";
  s << "  GROUND_TRUTH_POSE: " << truth_poses << " messages\n";
  s << "  OMNI_FEATURES: " << frames << " frames, " << features << " features (at most " << max_features_per_frame
    << " per frame), max |bearing| " << max_abs_bearing_rad << " rad; " << frames_before_odometry
    << " frames before the first odometry sample";
  if (frames_still_skipped > 0) s << "; " << frames_still_skipped << " frames of a still robot left out (diagnostic)";
  s << "\n";
  s << "  measurements: " << measurements << " = " << landmark_sightings << " of landmarks + " << robot_sightings
    << " of other robots ("
    << (robot_sightings_dropped > 0 ? "dropped: " + std::to_string(robot_sightings_dropped)
                                    : std::string("kept as clutter"))
    << ") + " << unknown_code_sightings << " unknown barcodes (kept as clutter:";
  for (int c : unknown_codes) s << " " << c;
  s << ") + " << own_code_sightings << " of the robot's own barcode (kept as clutter)\n";
  if (start_pose)
    s << "  start pose (truth at the first frame with odometry, utime " << start_frame_utime << "): x "
      << start_pose->x_m << " m, y " << start_pose->y_m << " m, theta " << start_pose->theta_rad << " rad";
  else s << "  start pose: none (no frame within the odometry)";
  return s.str();
}

std::vector<slam::Landmark> truthLandmarks(const std::string& dataset_dir) {
  std::vector<slam::Landmark> out;
  for (const auto& l : readLandmarks(file(dataset_dir, "Landmark_Groundtruth.dat"))) {
    slam::Landmark L;
    L.id = static_cast<std::uint64_t>(l.subject);
    L.kind = slam::LandmarkKind::kVerticalLine;
    L.p_LinW_m = Eigen::Vector3d(l.x_m, l.y_m, 0.0);
    L.cov_LinW_m2 =
        Eigen::Vector3d(std::max(l.x_sigma_m * l.x_sigma_m, 1e-10), std::max(l.y_sigma_m * l.y_sigma_m, 1e-10), 1.0)
            .asDiagonal();
    out.push_back(L);
  }
  return out;
}

}  // namespace omnislam::mrclam
