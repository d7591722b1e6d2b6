// The features detectors' size and format check (procs/features/detectors.cpp): the size is judged
// first (a 3-channel frame of another size is reported by its size, not as "3 channels"), and the message
// gives what came and what the camera needs; the same check on a header (vision::HeaderProbe), as
// omnislam-features runs it before decoding, gives the same message.
#include <gtest/gtest.h>

#include "detectors.h"
#include "omnislam/vision/image_decode.h"

using namespace omnislam;

namespace {

const std::string kSrc = OMNISLAM_SOURCE_DIR;

std::string why(const features::Detector& det, const cv::Mat& img) { return det.check(img).value_or("(accepted)"); }

TEST(DetectorCheck, SizeIsReportedFirstWithWhatCameAndWhatIsNeeded) {
  const auto lights = features::makeDetector(config::Node::loadFile(kSrc + "/config/features/ceiling_lights.yaml"));
  EXPECT_EQ(why(*lights, cv::Mat(240, 320, CV_8UC3, cv::Scalar::all(0))),
            "size 320x240 does not match the camera (received 320x240, 3 channels, 8-bit; the camera needs 640x480, "
            "8-bit grey)");
  EXPECT_EQ(why(*lights, cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(0))),
            "format does not match the camera (received 640x480, 3 channels, 8-bit; the camera needs 640x480, 8-bit "
            "grey)");
  EXPECT_EQ(why(*lights, cv::Mat(480, 640, CV_16UC1, cv::Scalar::all(0))),
            "format does not match the camera (received 640x480, 1 channel, 16-bit; the camera needs 640x480, 8-bit "
            "grey)");
  EXPECT_EQ(why(*lights, cv::Mat(480, 640, CV_8UC1, cv::Scalar::all(0))), "(accepted)");
  EXPECT_EQ(why(*lights, cv::Mat()), "empty image");
  const auto lines = features::makeDetector(config::Node::loadFile(kSrc + "/config/features/vertical_lines.yaml"));
  EXPECT_EQ(why(*lines, cv::Mat(768, 1024, CV_8UC4, cv::Scalar::all(0))),
            "format does not match the camera (received 1024x768, 4 channels, 8-bit; the camera needs 1024x768, 8-bit "
            "grey or BGR)");
  EXPECT_EQ(why(*lines, cv::Mat(768, 1024, CV_8UC3, cv::Scalar::all(0))), "(accepted)");
}

TEST(DetectorCheck, TheHeaderProbeGivesTheSameVerdictAsTheDecodedImage) {
  const auto lights = features::makeDetector(config::Node::loadFile(kSrc + "/config/features/ceiling_lights.yaml"));
  for (const int type : {CV_8UC1, CV_8UC3, CV_16UC1})
    for (const cv::Size size : {cv::Size(640, 480), cv::Size(1280, 960), cv::Size(480, 640)}) {
      vision::ImageHeader h;
      h.width_px = size.width, h.height_px = size.height, h.channels = CV_MAT_CN(type);
      h.bit_depth = CV_MAT_DEPTH(type) == CV_8U ? 8 : 16;
      const vision::HeaderProbe probe(h);
      const cv::Mat decoded(size.height, size.width, type, cv::Scalar::all(0));
      EXPECT_EQ(why(*lights, probe.image()), why(*lights, decoded)) << size << " " << cv::typeToString(type);
    }
}

}  // namespace
