// The options tables of the features config's detector sections (docs/design/detectors.md): per key
// its member, unit, accepted range and meaning (omnislam/core/options_field.h); the defaults are the
// vision structs' in-class values. The parser (detectors.cpp), the start-up echo (describe()) and the
// generated docs tables (omnislam-config-table lights | lines) all read them. Keys whose range depends
// on another key or on the camera (panorama centre, pad_columns, noise_sigma_grey's "auto") are read
// by hand beside them and listed in the docs by hand.
#pragma once

#include <string>
#include <vector>

#include "omnislam/core/options_field.h"
#include "omnislam/vision/ceiling_lights.h"
#include "omnislam/vision/vertical_lines.h"

namespace omnislam::features {

/// `ceiling_lights.*`: the lamp criteria (LampBlobOptions, CeilingLightOptions::blobs)...
const std::vector<options::Field<vision::LampBlobOptions>>& lampBlobFields();
/// ... and the rest of CeilingLightOptions (noise_sigma_grey apart: "auto" or a number).
const std::vector<options::Field<vision::CeilingLightOptions>>& ceilingLightFields();
/// `vertical_lines.*`: the panorama's radii and size (centre_u_px, centre_v_px, pad_columns apart)...
const std::vector<options::Field<vision::PanoramaOptions>>& panoramaFields();
/// ... and the line criteria of VerticalLineOptions.
const std::vector<options::Field<vision::VerticalLineOptions>>& verticalLineFields();

/// "key=value ..." of every key of the section (the start-up echo).
std::string describeOptions(const vision::CeilingLightOptions& o);
std::string describeOptions(const vision::VerticalLineOptions& o);

/// The docs tables' rows (omnislam-config-table lights | lines), keys written in full.
std::string lightsKeysMarkdown();
std::string linesKeysMarkdown();

}  // namespace omnislam::features
