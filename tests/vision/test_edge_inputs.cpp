// Edge inputs of the vision library: plots of values near the largest double or far from the
// origin end (their grid loops stop), a vertical-line panorama without the
// wrapped columns the seam needs is refused, and so are an automatic row count beyond the limit and
// a panorama of more pixels than the bound.
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

// 20000 x 20000 passes each side's bound but would ask for about 8 GB of remap tables when the
// detector is built: the product is bounded too, at exactly 2^24 pixels.
TEST(VisionEdgeInputs, APanoramaOfMoreThanTwoToTheTwentyFourPixelsIsRefused) {
  PanoramaOptions o;
  o.centre_u_px = 320, o.centre_v_px = 240, o.r_min_px = 40, o.r_max_px = 200;
  o.columns = 4048, o.pad_columns = 24, o.rows = 4096;  // 4096 x 4096
  EXPECT_FALSE(validate(o).has_value()) << *validate(o);
  o.rows = 4097;
  ASSERT_TRUE(validate(o).has_value());
  EXPECT_EQ(*validate(o),
            "rows x (columns + 2 pad_columns) = 4097 x 4096 = 16781312 pixels, more than 16777216 "
            "(4096 x 4096); lower columns or rows");
  o.rows = 20000, o.columns = 20000;
  EXPECT_TRUE(validate(o).has_value());
  // With rows 0 the count follows the radii: 1091 rows x 20047 columns.
  o.rows = 0, o.columns = 19999, o.pad_columns = 24, o.r_min_px = 110, o.r_max_px = 1200;
  ASSERT_TRUE(validate(o).has_value());
  EXPECT_NE(validate(o)->find("1091 x 20047 = 21871277 pixels"), std::string::npos) << *validate(o);
  EXPECT_NE(validate(o)->find("(rows 0: one per pixel of r_max_px - r_min_px)"), std::string::npos) << *validate(o);
}

}  // namespace
