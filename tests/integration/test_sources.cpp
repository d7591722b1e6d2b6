// The non-simulated sources: capture from a folder of images, odometry from a wheel-data CSV.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <csignal>
#include <cmath>
#include <fstream>

#include "omnislam/image_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/image_msg.h"
#include "omnislam/odometry_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/process_status_t.hpp"
#include "bus_util.h"
#include "proc_util.h"

using namespace omnislam;
namespace t = omnislam::testing;

namespace {

template <class Msg>
struct Collector {
  explicit Collector(lcm::LCM& lcm, const std::string& channel) {
    lcm.subscribe(channel, &Collector::on, this)->setQueueCapacity(10000);
  }
  void on(const lcm::ReceiveBuffer*, const std::string&, const Msg* m) { got.push_back(*m); }
  std::vector<Msg> got;
};

TEST(CaptureDir, PublishesTheFolderInNameOrderAndSkipsUnreadableFiles) {
  t::TempDir dir;
  for (int i = 0; i < 3; ++i) {
    cv::Mat img(48, 64, CV_8UC1, cv::Scalar(40 * (i + 1)));
    cv::imwrite(dir.file("img_" + std::to_string(i) + ".png"), img);
  }
  std::ofstream(dir.file("img_1b.png")) << "not a png";  // sorts between 1 and 2
  const std::string url = t::privateUdpUrl(5);
  lcm::LCM lcm(url);
  Collector<image_t> images(lcm, channels::kOmniImage);
  t::Child cap({t::binPath("omnislam-capture"), "--source", "dir", "--dir", dir.path(), "--rate-hz", "2", "--speedup",
                "0", "--start-utime", "5000000", "--url", url, "--format", "png"});
  t::handleUntil(
      lcm, [&] { return images.got.size() >= 3; }, 10.0);
  const auto r = cap.wait(10.0);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(images.got.size(), 3u) << r.output;
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(images.got[i].seq, i);
    const auto img = lcmio::decodeImage(images.got[i]);
    ASSERT_TRUE(img.has_value());
    EXPECT_EQ(img->at<uint8_t>(0, 0), 40 * (i + 1)) << "name order";
  }
  // utime follows the file index at the configured rate (the unreadable file keeps its slot).
  EXPECT_EQ(images.got[0].utime, 5'000'000);
  EXPECT_EQ(images.got[1].utime, 5'500'000);
  EXPECT_EQ(images.got[2].utime, 6'500'000);
  EXPECT_NE(r.output.find("rejected image file: " + dir.file("img_1b.png") +
                          ": not a PNG, JPEG, BMP or PGM/PPM/PBM image (unknown signature); skipped"),
            std::string::npos)
      << r.output;
}

TEST(OdometryCsv, IntegratesRecordedWheelData) {
  t::TempDir dir;
  // 2 s at 0.5 m/s straight, then 2 s turning at pi/4 rad/s on the spot, sampled at 20 Hz.
  std::ofstream csv(dir.file("wheels.csv"));
  csv.precision(17);
  csv << "utime,v_mps,omega_radps\n";
  int n = 0;
  for (int k = 0; k <= 80; ++k, ++n) {
    const bool straight = k < 40;
    csv << 1'000'000 + k * 50'000 << "," << (straight ? 0.5 : 0.0) << "," << (straight ? 0.0 : M_PI / 4) << "\n";
  }
  csv.close();
  const std::string url = t::privateUdpUrl(6);
  lcm::LCM lcm(url);
  Collector<odometry_t> odo(lcm, channels::kOdometry);
  t::Child p({t::binPath("omnislam-odometry"), "--source", "csv", "--csv", dir.file("wheels.csv"), "--speedup", "20",
              "--url", url});
  t::handleUntil(
      lcm, [&] { return static_cast<int>(odo.got.size()) >= n; }, 10.0);
  const auto r = p.wait(10.0);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(static_cast<int>(odo.got.size()), n) << r.output;
  const auto& last = odo.got.back();
  EXPECT_NEAR(last.x_m, 1.0, 1e-9);
  EXPECT_NEAR(last.y_m, 0.0, 1e-9);
  EXPECT_NEAR(last.theta_rad, M_PI / 2, 1e-9);
  EXPECT_EQ(last.utime, 1'000'000 + 80 * 50'000);
}

const process_status_t* lastStatusOf(const std::vector<process_status_t>& all, const std::string& name) {
  const process_status_t* last = nullptr;
  for (const auto& st : all)
    if (st.name == name) last = &st;
  return last;
}

// An RGBA or grey + alpha PNG is an ordinary image (the alpha is dropped); an image every receiver
// would refuse (9000 x 2: the contract's sides are 1..8192) is reported and not published (refused
// from its header, before decoding); the
// last status says whether the folder was gone through; and a
// tiny speedup waits instead of overflowing into "publish everything at once".
TEST(CaptureDir, AlphaIsDroppedARefusedImageIsNotPublishedAndTheLastStatusTellsTheEnd) {
  t::TempDir dir;
  cv::imwrite(dir.file("a_rgba.png"), cv::Mat(24, 32, CV_8UC4, cv::Scalar(10, 20, 30, 128)));
  {  // OpenCV cannot write grey + alpha (it reads it as BGRA): a 4 x 3 PNG of colour type 4, grey 77, alpha 200
    const unsigned char graya[] = {
        0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00,
        0x00, 0x04, 0x00, 0x00, 0x00, 0x03, 0x08, 0x04, 0x00, 0x00, 0x00, 0x1e, 0xfd, 0x66, 0x4d, 0x00, 0x00, 0x00,
        0x0f, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0xf0, 0x3d, 0x01, 0x81, 0x0c, 0x18, 0x0c, 0x00, 0xac, 0x83,
        0x0c, 0xfd, 0x4d, 0x82, 0x85, 0xd9, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};
    std::ofstream(dir.file("b_graya.png"), std::ios::binary).write(reinterpret_cast<const char*>(graya), sizeof graya);
  }
  cv::imwrite(dir.file("c_wide.png"), cv::Mat(2, 9000, CV_8UC1, cv::Scalar(5)));
  cv::imwrite(dir.file("d.png"), cv::Mat(24, 32, CV_8UC1, cv::Scalar(1)));
  cv::imwrite(dir.file("e.png"), cv::Mat(24, 32, CV_8UC1, cv::Scalar(2)));
  {
    const std::string url = t::privateUdpUrl(8);
    lcm::LCM lcm(url);
    Collector<image_t> images(lcm, channels::kOmniImage);
    Collector<process_status_t> status(lcm, channels::kProcessStatus);
    t::Child cap({t::binPath("omnislam-capture"), "--source", "dir", "--dir", dir.path(), "--speedup", "0",
                  "--start-utime", "1000000", "--url", url, "--format", "bgr"});
    t::handleUntil(
        lcm,
        [&] {
          const auto* st = lastStatusOf(status.got, "capture");
          return st && st->state == process_status_t::STATE_FINISHED;
        },
        10.0);
    const auto r = cap.wait(10.0);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    ASSERT_EQ(images.got.size(), 4u) << r.output;
    const auto rgba = lcmio::decodeImage(images.got[0]);
    ASSERT_TRUE(rgba.has_value());
    EXPECT_EQ(rgba->channels(), 3);
    EXPECT_EQ(rgba->at<cv::Vec3b>(0, 0), cv::Vec3b(10, 20, 30));
    const auto graya = lcmio::decodeImage(images.got[1]);
    ASSERT_TRUE(graya.has_value());
    EXPECT_EQ(graya->at<cv::Vec3b>(0, 0), cv::Vec3b(77, 77, 77)) << "the grey channel, not the alpha";
    EXPECT_EQ(images.got[2].utime, 4'000'000) << "d.png keeps its slot after the refused c_wide.png";
    EXPECT_EQ(images.got[2].seq, 2) << "the refused image used no seq";
    EXPECT_NE(r.output.find("c_wide.png: 9000x2, 1 channel, 8-bit PNG: a side beyond the limit of 8192 px; skipped"),
              std::string::npos)
        << r.output;
    const auto* st = lastStatusOf(status.got, "capture");
    ASSERT_NE(st, nullptr);
    EXPECT_EQ(st->state, process_status_t::STATE_FINISHED);
    EXPECT_EQ(st->detail, "finished: 4 of 5 images published");
    EXPECT_EQ(st->messages_out, 4);
  }
  {
    const std::string url = t::privateUdpUrl(9);
    lcm::LCM lcm(url);
    Collector<image_t> images(lcm, channels::kOmniImage);
    Collector<process_status_t> status(lcm, channels::kProcessStatus);
    t::Child cap({t::binPath("omnislam-capture"), "--source", "dir", "--dir", dir.path(), "--rate-hz", "1", "--speedup",
                  "1e-300", "--start-utime", "1000000", "--url", url});
    ASSERT_TRUE(t::handleUntil(
        lcm, [&] { return !images.got.empty(); }, 10.0));
    t::handleFor(lcm, 1.0);
    EXPECT_EQ(images.got.size(), 1u) << "the second image is due in 1e300 s, not at once";
    cap.signal(SIGINT);
    const auto r = cap.wait(10.0);
    t::handleFor(lcm, 0.3);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const auto* st = lastStatusOf(status.got, "capture");
    ASSERT_NE(st, nullptr);
    EXPECT_EQ(st->state, process_status_t::STATE_STOPPING) << "not FINISHED: 4 files were never read";
    EXPECT_EQ(st->detail, "interrupted: 1 of 5 images published");
  }
}

TEST(OdometryCsv, AStopPartWayIsNotReportedAsFinished) {
  t::TempDir dir;
  std::ofstream(dir.file("w.csv")) << "utime,v_mps,omega_radps\n1000000,0.1,0\n2000000,0.1,0\n3000000,0.1,0\n";
  const std::string url = t::privateUdpUrl(10);
  lcm::LCM lcm(url);
  Collector<odometry_t> odo(lcm, channels::kOdometry);
  Collector<process_status_t> status(lcm, channels::kProcessStatus);
  t::Child p({t::binPath("omnislam-odometry"), "--source", "csv", "--csv", dir.file("w.csv"), "--speedup", "1e-300",
              "--url", url});
  ASSERT_TRUE(t::handleUntil(
      lcm, [&] { return !odo.got.empty(); }, 10.0));
  t::handleFor(lcm, 0.5);
  EXPECT_EQ(odo.got.size(), 1u) << "the second row is due in 1e300 s";
  p.signal(SIGINT);
  const auto r = p.wait(10.0);
  t::handleFor(lcm, 0.3);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const auto* st = lastStatusOf(status.got, "odometry");
  ASSERT_NE(st, nullptr);
  EXPECT_EQ(st->state, process_status_t::STATE_STOPPING);
  EXPECT_EQ(st->detail, "interrupted: 1 of 3 rows published");
}

// The test publisher's last status says it finished, not "starting".
TEST(PublishSamples, ItsLastStatusSaysItFinishedAndHowManyRounds) {
  const std::string url = t::privateUdpUrl(11);
  lcm::LCM lcm(url);
  Collector<process_status_t> status(lcm, channels::kProcessStatus);
  t::Child p({t::binPath("omnislam-publish-samples"), "--duration", "0.3", "--period", "0.1", "--url", url});
  const auto r = p.wait(10.0);
  t::handleFor(lcm, 0.3);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const auto* st = lastStatusOf(status.got, "publish-samples");
  ASSERT_NE(st, nullptr);
  EXPECT_EQ(st->state, process_status_t::STATE_FINISHED);
  EXPECT_EQ(st->detail.rfind("finished: ", 0), 0u) << st->detail;
  EXPECT_NE(r.output.find("published "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(st->detail.substr(std::string("finished: ").size())), std::string::npos)
      << "the status and stderr count the same rounds: " << st->detail << " / " << r.output;
}

// The simulated sources follow GROUND_TRUTH_POSE. When the truth starts a new timeline (the
// simulator run again on the same bus, a truth log replayed again), each is a new run: capture
// publishes the second run's images (its image clock does not wait for the first run's next image
// time), and odometry does not integrate the jump back to the start as one step driven in negative
// time.
TEST(SimSources, ANewTruthTimelineIsANewRunForCaptureAndOdometry) {
  const std::string url = t::privateUdpUrl(7);
  lcm::LCM lcm(url);
  Collector<image_t> images(lcm, channels::kOmniImage);
  Collector<odometry_t> odo(lcm, channels::kOdometry);
  Collector<process_status_t> status(lcm, channels::kProcessStatus);
  const std::string world = t::sourcePath("config/worlds/sports_hall.yaml");
  t::Child cap({t::binPath("omnislam-capture"), "--source", "sim", "--world", world, "--url", url});
  t::Child od({t::binPath("omnislam-odometry"), "--source", "sim", "--world", world, "--url", url});
  ASSERT_TRUE(t::handleUntil(
      lcm,
      [&] {
        bool c = false, o = false;
        for (const auto& st : status.got) {
          c = c || st.name == "capture";
          o = o || st.name == "odometry";
        }
        return c && o;
      },
      10.0))
      << "both processes announce themselves once subscribed";
  constexpr int64_t kStart = 1'700'000'000'000'000;  // the world's start_utime
  int64_t seq = 0;
  const auto run = [&](int64_t n_samples) {  // 50 Hz truth along x at 0.27 m/s
    for (int64_t k = 0; k < n_samples; ++k) {
      pose_t p{};
      p.utime = kStart + k * 20'000;
      p.seq = seq++;
      p.x_m = 6.0 + 0.27 * k * 0.02;
      p.y_m = -3.25;
      lcm.publish(channels::kGroundTruthPose, &p);
      t::handleFor(lcm, 0.002);
    }
  };
  run(301);  // 0..6 s: images at 0, 1, ..., 6 s
  ASSERT_TRUE(t::handleUntil(
      lcm, [&] { return images.got.size() >= 7 && odo.got.size() >= 301; }, 10.0))
      << images.got.size() << " images, " << odo.got.size() << " odometry";
  const size_t first_images = images.got.size(), first_odo = odo.got.size();
  // The same 6 s again (a step back of 5 s or more is a new timeline): the node takes it at its
  // third message.
  run(301);
  t::handleUntil(
      lcm, [&] { return images.got.size() >= first_images + 7 && odo.got.size() >= first_odo + 299; }, 10.0);
  cap.signal(SIGINT);
  od.signal(SIGINT);
  const auto rc = cap.wait(10.0), ro = od.wait(10.0);
  // The truth at 0 and 0.02 s is refused until the third message confirms the new timeline, so
  // the image of time 0 is taken at 0.04 s (the first truth sample at or after it), then 1..6 s.
  ASSERT_EQ(images.got.size(), first_images + 7) << rc.output;
  for (size_t i = first_images; i < images.got.size(); ++i) {
    const int64_t k = static_cast<int64_t>(i - first_images);
    EXPECT_EQ(images.got[i].utime, kStart + (k == 0 ? 40'000 : k * 1'000'000)) << i;
    EXPECT_EQ(images.got[i].seq, k) << "seq starts again";
  }
  EXPECT_NE(rc.output.find("new timeline"), std::string::npos) << rc.output;
  ASSERT_EQ(odo.got.size(), first_odo + 299) << ro.output;
  const odometry_t& again = odo.got[first_odo];
  EXPECT_EQ(again.utime, kStart + 2 * 20'000);
  EXPECT_EQ(again.seq, 0) << "seq starts again";
  EXPECT_EQ(again.v_mps, 0.0) << "no velocity across the two runs";
  EXPECT_LT(std::hypot(again.x_m, again.y_m), 1e-9) << "the odometry frame is the new run's first pose";
  EXPECT_NEAR(odo.got.back().x_m, 0.27 * 5.96, 0.2) << "and integrates the new run from there";
  EXPECT_NE(ro.output.find("new timeline"), std::string::npos) << ro.output;
  // Stopped by SIGINT: the last status says so (it said "running" before).
  t::handleFor(lcm, 0.3);
  const auto* sc = lastStatusOf(status.got, "capture");
  const auto* so = lastStatusOf(status.got, "odometry");
  ASSERT_TRUE(sc && so);
  EXPECT_EQ(sc->state, process_status_t::STATE_STOPPING);
  // (The node appends the new timeline it took on its input.)
  EXPECT_EQ(sc->detail,
            "stopped after " + std::to_string(images.got.size()) + " images [inputs restarted: 0 seq, 1 utime]");
  EXPECT_EQ(so->state, process_status_t::STATE_STOPPING);
  EXPECT_EQ(so->detail,
            "stopped after " + std::to_string(odo.got.size()) + " messages [inputs restarted: 0 seq, 1 utime]");
}

}  // namespace
