// Edge inputs of the vision library found by an audit: plots of values near the largest double or
// far from the origin end (their grid loops never did), a vertical-line panorama without the
// wrapped columns the seam needs is refused, and so is an automatic row count beyond the limit.
#include <gtest/gtest.h>

#include <limits>

#include "omnislam/vision/panorama.h"
#include "omnislam/vision/plots.h"
#include "omnislam/vision/vertical_lines.h"

using namespace omnislam;
using namespace omnislam::vision;

namespace {

TEST(VisionEdgeInputs, PlotsOfHugeOrFarValuesReturn) {
  ErrorPlot ep;
  ep.t_s = {0.0, 1.0, 2.0};
  ep.position_err_m = {0.1, 1.7e308, 0.2};  // ymax * 1.1 overflowed to inf: g += inf forever
  ep.heading_err_rad = {0.0, 0.1, 0.2};
  EXPECT_EQ(renderErrorPlot(ep).rows, 520);
  MapPlot mp;
  mp.estimate = {Pose2{1e16, 0.0, 0.0}, Pose2{1e16 + 2.0, 1.0, 0.0}};  // g += 0.5 no longer changes g
  mp.truth = mp.estimate;
  EXPECT_EQ(renderMapPlot(mp).rows, 700);
}

TEST(VisionEdgeInputs, VerticalLinesNeedTwoWrappedColumnsAtTheSeam) {
  VerticalLineOptions o;
  o.panorama.centre_u_px = 320, o.panorama.centre_v_px = 240, o.panorama.r_min_px = 40, o.panorama.r_max_px = 200;
  for (const int pad : {0, 1}) {
    o.panorama.pad_columns = pad;
    ASSERT_TRUE(validate(o).has_value()) << pad;
    EXPECT_EQ(*validate(o), "panorama pad_columns must be >= 2 for vertical lines");
  }
  o.panorama.pad_columns = 2;
  EXPECT_FALSE(validate(o).has_value()) << *validate(o);
}

TEST(VisionEdgeInputs, AnAutomaticRowCountBeyondTheLimitIsRefused) {
  PanoramaOptions o;
  o.centre_u_px = 320, o.centre_v_px = 240, o.r_min_px = 0, o.r_max_px = 99999, o.columns = 720;
  ASSERT_TRUE(validate(o).has_value());  // 100000 rows: 8 GB of maps
  EXPECT_NE(validate(o)->find("r_max_px - r_min_px <= 19999"), std::string::npos) << *validate(o);
  o.r_max_px = 19999;
  EXPECT_FALSE(validate(o).has_value()) << *validate(o);
}

}  // namespace
