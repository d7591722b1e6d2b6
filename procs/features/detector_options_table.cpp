// The detector sections' options tables (see detector_options_table.h): one row per key.
#include "detector_options_table.h"

#include "omnislam/config/options_parse.h"

namespace omnislam::features {

namespace {

using options::Bounds;
using options::enumeration;
using options::integer;
using options::real;
constexpr Bounds kC = Bounds::kClosed;

const std::vector<std::string>& truncatedBlobNames() {
  static const std::vector<std::string> n{"drop", "keep"};
  return n;
}

}  // namespace

// One row per key: not reformatted.
// clang-format off
const std::vector<options::Field<vision::LampBlobOptions>>& lampBlobFields() {
  using B = vision::LampBlobOptions;
  static const std::vector<options::Field<B>> t{
      integer<B>("background_window_px", &B::background_window_px, "blobs.background_window_px", 0, 255, "median window of the background: 0 (from background_window_rad) or odd, 3..255"),
      real<B>("noise_margin_sigma", &B::noise_margin_sigma, "blobs.noise_margin_sigma", "", 0.1, 100, kC, "core above B by this many noise sigmas (5: ~0.07 noise pixels per 640 x 480 frame)"),
      real<B>("min_noise_sigma_grey", &B::min_noise_sigma_grey, "blobs.min_noise_sigma_grey", "grey", 0.01, 100, kC, "floor of the per-frame noise estimate (quantisation, flat synthetic images)"),
      real<B>("min_source_ratio", &B::min_source_ratio, "blobs.min_source_ratio", "", 1, 1000, kC, "unclipped core: I - black >= ratio x (B - black)"),
      integer<B>("saturation_grey", &B::saturation_grey, "blobs.saturation_grey", 1, 255, "clip level of the encoding (JPEG: 250..255)"),
      real<B>("min_peak_ratio", &B::min_peak_ratio, "blobs.min_peak_ratio", "", 0, 1000, kC, "unclipped blob: peak - black >= ratio x (median - black)"),
      real<B>("min_surround_contrast", &B::min_surround_contrast, "blobs.min_surround_contrast", "", 0, 1, kC, "contrast over the ring's lower quartile"),
      integer<B>("threshold_grey", &B::threshold_grey, "blobs.threshold_grey", 0, 254, "optional absolute level (0 = none)"),
      integer<B>("min_area_px", &B::min_area_px, "blobs.min_area_px", 1, 1e6, "smaller blobs are noise"),
      integer<B>("max_area_px", &B::max_area_px, "blobs.max_area_px", 1, 1e7, "larger blobs are dropped; >= min_area_px"),
      integer<B>("connectivity", &B::connectivity, "blobs.connectivity", 4, 8, "4 or 8"),
  };
  return t;
}

const std::vector<options::Field<vision::CeilingLightOptions>>& ceilingLightFields() {
  using L = vision::CeilingLightOptions;
  static const std::vector<options::Field<L>> t{
      real<L>("background_window_rad", &L::background_window_rad, "background_window_rad", "rad", 1e-3, 1, kC, "angular window (x the camera's px/rad) when background_window_px is 0"),
      real<L>("max_elongation", &L::max_elongation, "max_elongation", "", 1, 100, kC, "shape filter, unclipped blobs"),
      real<L>("max_clipped_elongation", &L::max_clipped_elongation, "max_clipped_elongation", "", 1, 100, kC, "shape filter, clipped blobs (tubes); >= max_elongation, and at least it when not given"),
      real<L>("pixel_sigma_floor_px", &L::pixel_sigma_floor_px, "pixel_sigma_floor_px", "px", 1e-3, 100, kC, "added in quadrature to the centroid sigma (0.03 in config/features/ceiling_lights.yaml)"),
      enumeration<L>("truncated_blobs", "truncated_blobs", truncatedBlobNames(), [](const L& o) { return static_cast<int>(o.truncated_blobs); },
                     [](L& o, int i) { o.truncated_blobs = static_cast<vision::TruncatedBlobs>(i); },
                     "blobs cut by the border or mask: dropped or kept"),
  };
  return t;
}

const std::vector<options::Field<vision::PanoramaOptions>>& panoramaFields() {
  using P = vision::PanoramaOptions;
  static const std::vector<options::Field<P>> t{
      real<P>("r_min_px", &P::r_min_px, "panorama.r_min_px", "px", 0, 1e5, kC, "inner radius of the radial band (position filter)"),
      real<P>("r_max_px", &P::r_max_px, "panorama.r_max_px", "px", 1, 1e5, kC, "outer radius; > r_min_px + 1"),
      integer<P>("columns", &P::columns, "panorama.columns", 36, 20000, "columns over 360 deg"),
      integer<P>("rows", &P::rows, "panorama.rows", 0, 20000, "0 = one per radial pixel, else >= 2; rows x (columns + 2 pad_columns) at most 2^24 pixels"),
  };
  return t;
}

const std::vector<options::Field<vision::VerticalLineOptions>>& verticalLineFields() {
  using V = vision::VerticalLineOptions;
  static const std::vector<options::Field<V>> t{
      integer<V>("edge_threshold", &V::edge_threshold, "edge_threshold", 1, 1020, "on |Sobel gx| of 8-bit grey"),
      integer<V>("min_run_rows", &V::min_run_rows, "min_run_rows", 1, 100000, "shorter runs are noise"),
      integer<V>("max_gap_rows", &V::max_gap_rows, "max_gap_rows", 0, 100000, "gaps bridged inside a run"),
      integer<V>("merge_columns", &V::merge_columns, "merge_columns", 0, 20, "runs this many columns apart may be one line"),
      integer<V>("merge_gap_rows", &V::merge_gap_rows, "merge_gap_rows", 0, 100000, "runs of one line may be this far apart along it"),
      integer<V>("min_length_rows", &V::min_length_rows, "min_length_rows", 1, 100000, "shortest line kept (panorama rows)"),
      real<V>("max_drift_columns", &V::max_drift_columns, "max_drift_columns", "", 0.01, 1000, kC, "a line may drift this many columns end to end (else slanted)"),
      real<V>("max_rms_columns", &V::max_rms_columns, "max_rms_columns", "", 0.01, 1000, kC, "rms of the rows about the line fit above which the rows are not one radial edge"),
      integer<V>("colour_offset_columns", &V::colour_offset_columns, "colour_offset_columns", 1, 1000, "colour strips start this far from the line"),
      integer<V>("colour_width_columns", &V::colour_width_columns, "colour_width_columns", 1, 1000, "and are this wide"),
      real<V>("pixel_sigma_px", &V::pixel_sigma_px, "pixel_sigma_px", "px", 1e-3, 100, kC, "tangential pixel noise -> azimuth variance"),
      real<V>("max_opposite_fraction", &V::max_opposite_fraction, "max_opposite_fraction", "", 0, 1, kC, "junction chains (checkerboards), step 7 (1 = off)"),
      real<V>("bar_max_width_px", &V::bar_max_width_px, "bar_max_width_px", "px", 0, 1000, kC, "the two sides of a thinner bar are one line, step 7b (0 = off); twice the measured edge-response FWHM"),
      integer<V>("cell_row_min_lines", &V::cell_row_min_lines, "cell_row_min_lines", 0, 100, "rows of square cells (checkerboards), step 7a (0 = off)"),
      real<V>("cell_max_aspect", &V::cell_max_aspect, "cell_max_aspect", "", 1, 10, kC, "a cell's length / spacing within this factor"),
      real<V>("cell_max_spacing_ratio", &V::cell_max_spacing_ratio, "cell_max_spacing_ratio", "", 1, 10, kC, "consecutive spacings within this factor"),
      real<V>("contrast_exponent", &V::contrast_exponent, "contrast_exponent", "", 0, 1, kC, "p of the contrast normalisation, step 2 (0 = off)"),
      real<V>("contrast_reference_grey", &V::contrast_reference_grey, "contrast_reference_grey", "grey", 1, 255, kC, "ref: the threshold holds at this mean grey"),
      real<V>("contrast_offset_grey", &V::contrast_offset_grey, "contrast_offset_grey", "grey", 0, 255, kC, "off"),
      integer<V>("contrast_window_columns", &V::contrast_window_columns, "contrast_window_columns", 1, 100, "half width of the local-mean box"),
      real<V>("clahe_clip_limit", &V::clahe_clip_limit, "clahe_clip_limit", "", 0, 100, kC, "CLAHE on the panorama (0 = off)"),
      integer<V>("clahe_tile_columns", &V::clahe_tile_columns, "clahe_tile_columns", 8, 20000, "CLAHE tiles of this many panorama pixels"),
  };
  return t;
}
// clang-format on

std::string describeOptions(const vision::CeilingLightOptions& o) {
  return options::describeFields(o.blobs, lampBlobFields()) + " " + options::describeFields(o, ceilingLightFields()) +
         " noise_sigma_grey=" + (o.noise_sigma_grey ? options::numberText(*o.noise_sigma_grey) : "auto");
}

std::string describeOptions(const vision::VerticalLineOptions& o) {
  const auto& p = o.panorama;
  return "centre_u_px=" + options::numberText(p.centre_u_px) + " centre_v_px=" + options::numberText(p.centre_v_px) +
         " " + options::describeFields(p, panoramaFields()) + " pad_columns=" + std::to_string(p.pad_columns) + " " +
         options::describeFields(o, verticalLineFields());
}

std::string lightsKeysMarkdown() {
  const vision::CeilingLightOptions d{};
  return config::markdownHeader() + config::markdownRows("ceiling_lights.", lampBlobFields(), d.blobs) +
         config::markdownRows("ceiling_lights.", ceilingLightFields(), d);
}

std::string linesKeysMarkdown() {
  const vision::VerticalLineOptions d{};
  return config::markdownHeader() +
         config::markdownRows("vertical_lines.", panoramaFields(), d.panorama, {"r_min_px", "r_max_px"}) +
         config::markdownRows("vertical_lines.", verticalLineFields(), d);
}

}  // namespace omnislam::features
