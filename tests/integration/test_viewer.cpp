// omnislam-viewer without a display. From a log: a synthetic recording (truth, image, features,
// SLAM pose, map, particles and associations for a few steps, plus a garbage SLAM_MAP event)
// rendered with --headless --log gives frame_<step>.png every N steps and final.png of the expected
// size with the landmarks, particles and associated features drawn. Live: the viewer on a private
// URL draws what is published, counts garbage on SLAM_MAP in PROCESS_STATUS and keeps running,
// and writes final.png on SIGTERM; a frame it cannot write is reported and the view goes on. Bad
// flags stop it with exit code 2. The global localiser: a log of SLAM_LOCALISATION only (two
// hypotheses, no SLAM step) with --map gives localisation_<n>.png and a final view with the saved
// map's lamps and the hypotheses; once a SLAM_POSE is newer, the hypotheses are gone.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <thread>

#include "omnislam/associations_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/image_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/image_msg.h"
#include "omnislam/map_t.hpp"
#include "omnislam/particles_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/process_status_t.hpp"
#include "omnislam/slam_localisation_t.hpp"
#include "omnislam/vision/slam_view.h"
#include "bus_util.h"
#include "omnislam/lcmio/log_writer.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;
namespace fs = std::filesystem;

namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr int kViewW = 820 + 720, kViewH = 720;  // the viewer's default map + image panel, height
const std::vector<Eigen::Vector3d> kLights = {{2, 2, 6.5}, {6, 2, 6.5}, {2, -3, 6.5}, {6, -3, 6.5}};

/// One synthetic SLAM step k (1 Hz): every message the viewer listens to, in publication order.
struct Step {
  std::vector<std::pair<std::string, std::vector<uint8_t>>> events;
  template <class Msg>
  void add(const std::string& ch, const Msg& m) {
    std::vector<uint8_t> buf(static_cast<size_t>(m.getEncodedSize()));
    m.encode(buf.data(), 0, static_cast<int>(buf.size()));
    events.emplace_back(ch, std::move(buf));
  }
};

pose_t pose(int64_t utime, int64_t seq, double x, double y, double th, bool truth) {
  pose_t p{};
  p.utime = utime, p.seq = seq, p.x_m = x, p.y_m = y, p.theta_rad = th;
  p.input_seq = truth ? -1 : seq;
  if (!truth) {
    p.covariance[0][0] = p.covariance[1][1] = 0.04, p.covariance[2][2] = 0.01;
    p.num_particles = 50, p.effective_sample_size = 30;
  }
  return p;
}

Step makeStep(int k) {
  Step s;
  const int64_t ut = kT0 + k * 1'000'000;
  const double x = 0.8 * k, y = 0.1 * k;
  for (int i = 0; i < 10; ++i)  // truth at 10 Hz up to the frame
    s.add(channels::kGroundTruthPose, pose(ut - 900'000 + i * 100'000, k * 10 + i, x - 0.08 * (9 - i), y, 0.0, true));
  if (k == 0) {
    map_t tm{};
    tm.utime = ut, tm.seq = 0, tm.input_seq = -1;
    for (size_t i = 0; i < kLights.size(); ++i) {
      landmark_t l{};
      l.id = static_cast<int64_t>(i);
      for (int j = 0; j < 3; ++j) l.position_m[j] = kLights[i][j];
      l.kind = 1;
      tm.landmarks.push_back(l);
    }
    tm.num_landmarks = static_cast<int32_t>(tm.landmarks.size());
    s.add(channels::kGroundTruthMap, tm);
  }
  // The image: bright blobs on black, and its features at the blobs.
  cv::Mat img(480, 640, CV_8UC1, cv::Scalar(10));
  features_t f{};
  f.utime = ut, f.seq = k, f.image_seq = k, f.detector = "test";
  for (int i = 0; i < 3; ++i) {
    const cv::Point c(200 + 120 * i, 150 + 80 * i);
    cv::circle(img, c, 6, cv::Scalar(250), cv::FILLED);
    feature_t ft{};
    ft.kind = feature_t::KIND_CEILING_LIGHT;
    ft.azimuth_rad = 0.5 * i, ft.elevation_rad = 1.0, ft.has_elevation = true;
    ft.covariance[0][0] = ft.covariance[1][1] = 1e-4;
    ft.u_px = c.x, ft.v_px = c.y;
    f.features.push_back(ft);
  }
  f.num_features = 3;
  image_t im{};
  im.utime = ut, im.seq = k, im.camera_name = "test";
  lcmio::encodeImage(img, image_t::FORMAT_GRAY8, im);
  s.add(channels::kOmniImage, im);
  s.add(channels::kOmniFeatures, f);
  // SLAM outputs of the frame.
  s.add(channels::kSlamPose, pose(ut, k, x + 0.05, y - 0.05, 0.02, false));
  map_t m{};
  m.utime = ut, m.seq = k, m.input_seq = k, m.num_candidates = 1;
  for (size_t i = 0; i < kLights.size(); ++i) {
    landmark_t l{};
    l.id = 10 + static_cast<int64_t>(i);
    for (int j = 0; j < 3; ++j) l.position_m[j] = kLights[i][j] + 0.1;
    l.covariance[0][0] = l.covariance[1][1] = 0.09, l.covariance[2][2] = 0.1;
    l.type = i < 2 ? 1 : 2;
    l.times_detected = 3;
    l.kind = 1;
    m.landmarks.push_back(l);
  }
  m.num_landmarks = static_cast<int32_t>(m.landmarks.size());
  s.add(channels::kSlamMap, m);
  particles_t p{};
  p.utime = ut, p.seq = k, p.input_seq = k, p.num_particles = 50;
  for (int i = 0; i < 50; ++i) {
    p.x_m.push_back(x + 0.3 * std::cos(i)), p.y_m.push_back(y + 0.3 * std::sin(i * 1.3));
    p.theta_rad.push_back(0.0), p.weight.push_back(1.0 / 50);
  }
  s.add(channels::kSlamParticles, p);
  associations_t a{};
  a.utime = ut, a.seq = k, a.input_seq = k, a.num_features = 3;
  a.landmark_id = {10, associations_t::NOT_ASSOCIATED, associations_t::NOT_USED};
  s.add(channels::kSlamAssociations, a);
  return s;
}

int countNear(const cv::Mat& img, const cv::Rect& r, const cv::Scalar& c, int tol) {
  cv::Mat mask;
  cv::inRange(img(r), c - cv::Scalar::all(tol), c + cv::Scalar::all(tol), mask);
  return cv::countNonZero(mask);
}

/// The view holds a map with landmarks and particles and an image with associated features.
void expectFullView(const std::string& path) {
  SCOPED_TRACE(path);
  ASSERT_TRUE(fs::exists(path));
  const cv::Mat img = cv::imread(path, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, kViewW);
  EXPECT_EQ(img.rows, kViewH);
  // Inside the plot area and the drawn image (the legends below them hold every colour too).
  const cv::Rect map(60, 100, 740, 520), image(830, 32, 700, 620);
  namespace vc = vision::view_colours;
  EXPECT_GT(countNear(img, map, vc::kLandmarkType1, 10), 20);
  EXPECT_GT(countNear(img, map, vc::kLandmarkType2, 10), 20);
  EXPECT_GT(countNear(img, map, vc::kParticle, 10), 20);
  EXPECT_GT(countNear(img, map, vc::kEstimate, 30), 20);
  EXPECT_GT(countNear(img, image, vc::kFeatAssociated, 20), 20);
  EXPECT_GT(countNear(img, image, vc::kFeatCandidate, 20), 20);
  EXPECT_GT(countNear(img, image, vc::kFeatNotUsed, 20), 20);
  // The image itself is there: its bright blobs.
  EXPECT_GT(countNear(img, image, cv::Scalar(250, 250, 250), 6), 50);
}

TEST(Viewer, HeadlessFromALogWritesEveryNthStepAndTheFinalView) {
  t::TempDir dir;
  const std::string log = dir.file("run.lcm"), out = dir.file("png");
  {
    lcmio::LogWriter lf(log);
    auto write = [&](const std::string& ch, const std::vector<uint8_t>& data) {
      lf.write(kT0 + (lf.events() + 1) * 1000, ch, data.data(), static_cast<int32_t>(data.size()));
    };
    for (int k = 0; k < 6; ++k) {
      for (const auto& [ch, data] : makeStep(k).events) write(ch, data);
      if (k == 2) write(channels::kSlamMap, std::vector<uint8_t>(37, 0xab));  // garbage
    }
  }
  const auto r =
      t::run({t::binPath("omnislam-viewer"), "--headless", "--log", log, "--out-dir", out, "--every", "2"}, 60);
  ASSERT_FALSE(r.timed_out) << r.output;
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("6 SLAM steps"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 decode errors"), std::string::npos) << r.output;
  // Steps are 1..6; a step is drawn when the next begins: 2 and 4 as frames, 6 in final.png.
  std::set<std::string> files;
  for (const auto& e : fs::directory_iterator(out)) files.insert(e.path().filename().string());
  EXPECT_EQ(files, (std::set<std::string>{"frame_000002.png", "frame_000004.png", "final.png"}));
  expectFullView(out + "/final.png");
  expectFullView(out + "/frame_000004.png");
  EXPECT_LT(fs::file_size(out + "/final.png"), 300u * 1024u);

  // A log cut inside an event (a recorder killed mid-write): the events before the cut are drawn
  // and the lost tail is named, where LCM's reader would just stop.
  const auto whole = fs::file_size(log);
  {
    std::ofstream app(log, std::ios::binary | std::ios::app);
    const char head[6] = {static_cast<char>(0xed),
                          static_cast<char>(0xa1),
                          static_cast<char>(0xda),
                          static_cast<char>(0x01),
                          0,
                          0};  // an event's sync word, then nothing
    app.write(head, sizeof head);
  }
  const auto cut =
      t::run({t::binPath("omnislam-viewer"), "--headless", "--log", log, "--out-dir", dir.file("png2")}, 60);
  ASSERT_EQ(cut.exit_code, 0) << cut.output;
  EXPECT_NE(cut.output.find("6 SLAM steps"), std::string::npos) << cut.output;
  EXPECT_NE(cut.output.find("the 6 bytes after its first"), std::string::npos) << cut.output;
  EXPECT_NE(cut.output.find("from byte " + std::to_string(whole)), std::string::npos) << cut.output;
  EXPECT_NE(cut.output.find("cannot be read (truncated or corrupt)"), std::string::npos) << cut.output;
}

/// The global localiser's state of frame k: ambiguous between the pose and its half-turned twin.
slam_localisation_t localisation(int k) {
  slam_localisation_t m{};
  m.utime = kT0 + k * 1'000'000, m.seq = k, m.input_seq = k;
  m.state = slam_localisation_t::STATE_AMBIGUOUS;
  m.num_hypotheses = 2, m.num_tracked = 3, m.num_frames = k + 1, m.num_reported = 2;
  m.x_m = {0.8 * k, 8.0 - 0.8 * k}, m.y_m = {0.0, -1.0}, m.theta_rad = {0.0, M_PI};
  std::vector<double> c(9, 0.0);
  c[0] = c[4] = 0.04, c[8] = 0.001;
  m.covariance = {c, c};
  m.relative_log_likelihood = {0.0, -1.5};
  m.frames_explained = {k + 1, k + 1};
  m.travel_m = {0.8 * k, 0.8 * k};
  return m;
}

TEST(Viewer, GlobalLocalisationHypothesesOverTheSavedMap) {
  t::TempDir dir;
  const std::string map = dir.file("map.yaml");
  {
    std::ofstream f(map);
    f << "format: omnislam-map\nversion: 2\nutime: 0\nnum_landmarks: " << kLights.size() << "\nlandmarks:\n";
    for (size_t i = 0; i < kLights.size(); ++i)
      f << "  - {id: " << i << ", kind: point3d, type: 1, counter: 5, position_m: [" << kLights[i].x() << ", "
        << kLights[i].y() << ", " << kLights[i].z() << "], covariance_m2: [0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.01]}\n";
    f << "end: omnislam-map\n";
  }
  auto writeLog = [&](const std::string& log, bool then_a_pose) {
    lcmio::LogWriter lf(log);
    Step s;
    for (int k = 0; k < 4; ++k) s.add(channels::kSlamLocalisation, localisation(k));
    if (then_a_pose) s.add(channels::kSlamPose, pose(kT0 + 4'000'000, 0, 3.2, 0.0, 0.0, false));
    for (const auto& [ch, data] : s.events)
      lf.write(kT0 + (lf.events() + 1) * 1000, ch, data.data(), static_cast<int32_t>(data.size()));
  };
  const cv::Rect plot(60, 100, 740, 520);
  namespace vc = vision::view_colours;
  for (const bool then_a_pose : {false, true}) {
    SCOPED_TRACE(then_a_pose ? "then a SLAM_POSE" : "localising");
    const std::string log = dir.file(then_a_pose ? "b.lcm" : "a.lcm"), out = dir.file(then_a_pose ? "b" : "a");
    writeLog(log, then_a_pose);
    const auto r = t::run({t::binPath("omnislam-viewer"), "--headless", "--log", log, "--out-dir", out, "--every", "2",
                           "--map", map, "--image-width", "0"},
                          60);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::set<std::string> files;
    for (const auto& e : fs::directory_iterator(out)) files.insert(e.path().filename().string());
    EXPECT_EQ(files, (std::set<std::string>{"localisation_000002.png", "localisation_000004.png", "final.png"}));
    const cv::Mat img = cv::imread(out + "/final.png", cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty());
    EXPECT_GT(countNear(img, plot, vc::kLandmarkType1, 10), 20) << "the saved map's lamps";
    const int teal = countNear(img, plot, vc::kHypothesis, 30);
    if (then_a_pose) EXPECT_EQ(teal, 0) << "no hypotheses once the filter tracks";
    else EXPECT_GT(teal, 40) << "two hypotheses";
    const cv::Mat early = cv::imread(out + "/localisation_000002.png", cv::IMREAD_COLOR);
    EXPECT_GT(countNear(early, plot, vc::kHypothesis, 30), 40);
  }
  const auto bad = t::run({t::binPath("omnislam-viewer"), "--headless", "--log", dir.file("a.lcm"), "--out-dir",
                           dir.file("c"), "--map", dir.file("a.lcm")},
                          60);
  EXPECT_NE(bad.exit_code, 0) << "a log is not a map";
  EXPECT_NE(bad.output.find("a.lcm"), std::string::npos) << bad.output;
}

/// Keeps the latest PROCESS_STATUS of each process.
struct StatusListener {
  explicit StatusListener(const std::string& url) : lcm(url) {
    lcm.subscribeFunction(channels::kProcessStatus, &StatusListener::on, this);
  }
  static void on(const lcm::ReceiveBuffer* rb, const std::string&, StatusListener* self) {
    process_status_t s;
    if (s.decode(rb->data, 0, static_cast<int>(rb->data_size)) > 0) self->status[s.name] = s;
  }
  lcm::LCM lcm;
  std::map<std::string, process_status_t> status;
};

TEST(Viewer, LiveHeadlessDrawsTheBusCountsGarbageAndWritesTheFinalViewOnSigterm) {
  const std::string url = t::privateUdpUrl(14);
  t::TempDir dir;
  const std::string out = dir.file("png");
  StatusListener bus(url);
  ASSERT_TRUE(bus.lcm.good());
  t::Child viewer({t::binPath("omnislam-viewer"), "--headless", "--url", url, "--out-dir", out, "--every", "1"});
  ASSERT_TRUE(t::handleUntil(
      bus.lcm, [&] { return bus.status.count("viewer") > 0; }, 10))
      << viewer.output();
  int64_t published = 0;
  auto publishStep = [&](int k) {
    for (const auto& [ch, data] : makeStep(k).events) {
      bus.lcm.publish(ch, data.data(), static_cast<unsigned>(data.size()));
      ++published;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  };
  publishStep(0);
  publishStep(1);
  const std::vector<uint8_t> garbage(53, 0x5a);
  bus.lcm.publish(channels::kSlamMap, garbage.data(), static_cast<unsigned>(garbage.size()));
  ++published;
  EXPECT_TRUE(t::handleUntil(
      bus.lcm, [&] { return bus.status["viewer"].decode_errors >= 1; }, 5))
      << "the viewer does not count the garbage SLAM_MAP\n"
      << viewer.output();
  EXPECT_TRUE(viewer.alive()) << viewer.output();
  for (int k = 2; k < 4; ++k) publishStep(k);
  // Steps 1..3 are complete (step 4 is still open): frame_000001..3.
  EXPECT_TRUE(t::handleUntil(
      bus.lcm, [&] { return fs::exists(out + "/frame_000003.png"); }, 10))
      << viewer.output();
  // Every message handled (its status counts them) before SIGTERM: wait for that, not a fixed pause.
  EXPECT_TRUE(t::handleUntil(
      bus.lcm, [&] { return bus.status["viewer"].messages_in >= published; }, 20))
      << bus.status["viewer"].messages_in << " of " << published << " messages handled\n"
      << viewer.output();
  viewer.signal(SIGTERM);
  const auto r = viewer.wait(15);
  ASSERT_FALSE(r.timed_out) << r.output;
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("decode error"), std::string::npos) << r.output;
  for (const char* f : {"frame_000001.png", "frame_000002.png", "frame_000003.png"})
    EXPECT_TRUE(fs::exists(out + "/" + f)) << f;
  expectFullView(out + "/frame_000003.png");
  expectFullView(out + "/final.png");
}

// A frame that cannot be written is reported, and the view goes on: the poses after it are applied
// (not refused, each retrying the same file), and the exit code says it.
TEST(Viewer, AFrameThatCannotBeWrittenIsReportedAndLaterPosesStillApply) {
  const std::string url = t::privateUdpUrl(16);
  t::TempDir dir;
  const std::string out = dir.file("png");
  fs::create_directories(out + "/frame_000002.png");  // a folder where the frame goes: imwrite fails
  StatusListener bus(url);
  ASSERT_TRUE(bus.lcm.good());
  t::Child viewer({t::binPath("omnislam-viewer"), "--headless", "--url", url, "--out-dir", out, "--every", "1"});
  ASSERT_TRUE(t::handleUntil(
      bus.lcm, [&] { return bus.status.count("viewer") > 0; }, 10))
      << viewer.output();
  int64_t published = 0;
  for (int k = 0; k < 6; ++k)
    for (const auto& [ch, data] : makeStep(k).events) {
      bus.lcm.publish(ch, data.data(), static_cast<unsigned>(data.size()));
      ++published;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  EXPECT_TRUE(t::handleUntil(
      bus.lcm, [&] { return fs::exists(out + "/frame_000005.png"); }, 10))
      << viewer.output();
  EXPECT_TRUE(t::handleUntil(
      bus.lcm, [&] { return bus.status["viewer"].messages_in >= published; }, 20))
      << bus.status["viewer"].messages_in << " of " << published << " messages handled\n"
      << viewer.output();
  EXPECT_EQ(bus.status["viewer"].rejected_inputs, 0) << "a good pose was refused\n" << viewer.output();
  viewer.signal(SIGTERM);
  const auto r = viewer.wait(15);
  ASSERT_FALSE(r.timed_out) << r.output;
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("6 SLAM steps"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("1 PNG FILES NOT WRITTEN (the first: cannot write '" + out + "/frame_000002.png')"),
            std::string::npos)
      << r.output;
  for (const char* f : {"frame_000001.png", "frame_000003.png", "frame_000004.png", "frame_000005.png", "final.png"})
    EXPECT_TRUE(fs::is_regular_file(out + "/" + f)) << f;
}

TEST(Viewer, BadFlagsStopWithExitCodeTwo) {
  t::TempDir dir;
  const auto no_out = t::run({t::binPath("omnislam-viewer"), "--headless"}, 10);
  EXPECT_EQ(no_out.exit_code, 2) << no_out.output;
  EXPECT_NE(no_out.output.find("--out-dir"), std::string::npos) << no_out.output;
  const std::string log = dir.file("empty.lcm");
  { lcm::LogFile lf(log, "w"); }
  const auto log_window = t::run({t::binPath("omnislam-viewer"), "--log", log}, 10);
  EXPECT_EQ(log_window.exit_code, 2) << log_window.output;
  EXPECT_NE(log_window.output.find("--headless"), std::string::npos) << log_window.output;
  const auto bad_value =
      t::run({t::binPath("omnislam-viewer"), "--headless", "--out-dir", dir.file("o"), "--every", "-1"}, 10);
  EXPECT_EQ(bad_value.exit_code, 2) << bad_value.output;
  EXPECT_NE(bad_value.output.find("--every"), std::string::npos) << bad_value.output;
  const auto no_display =
      t::run({t::binPath("omnislam-viewer"), "--url", t::privateUdpUrl(15)}, 10, {"DISPLAY=", "WAYLAND_DISPLAY="});
  EXPECT_EQ(no_display.exit_code, 2) << no_display.output;
  EXPECT_NE(no_display.output.find("--headless"), std::string::npos) << no_display.output;
}

}  // namespace
