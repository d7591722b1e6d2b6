// The non-simulated sources: capture from a folder of images, odometry from a wheel-data CSV.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgcodecs.hpp>

#include <chrono>
#include <cmath>
#include <fstream>

#include "omnislam/image_t.hpp"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/image_msg.h"
#include "omnislam/odometry_t.hpp"
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
  t::Child cap({t::binPath("omnislam-capture"), "--source", "dir", "--dir", dir.path(), "--rate-hz", "2",
                "--speedup", "0", "--start-utime", "5000000", "--url", url, "--format", "png"});
  t::handleUntil(lcm, [&] { return images.got.size() >= 3; }, 10.0);
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
  EXPECT_NE(r.output.find("img_1b.png; skipped"), std::string::npos) << r.output;
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
  t::handleUntil(lcm, [&] { return static_cast<int>(odo.got.size()) >= n; }, 10.0);
  const auto r = p.wait(10.0);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(static_cast<int>(odo.got.size()), n) << r.output;
  const auto& last = odo.got.back();
  EXPECT_NEAR(last.x_m, 1.0, 1e-9);
  EXPECT_NEAR(last.y_m, 0.0, 1e-9);
  EXPECT_NEAR(last.theta_rad, M_PI / 2, 1e-9);
  EXPECT_EQ(last.utime, 1'000'000 + 80 * 50'000);
}

}  // namespace
