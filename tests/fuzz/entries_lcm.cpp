// Fuzz entry points of the bus: a message's bytes decoded and validated as every receiver does
// (lcmio::decode, lcmio::validate; an image also through lcmio::decodeImage), and LCM log files read
// as omnislam-slam --replay, omnislam-eval and omnislam-logstat read them (lcmio::LogReader).
#include <cstdio>
#include <optional>
#include <string>

#include "entry_points.h"
#include "guard.h"
#include "omnislam/lcmio/channels.h"
#include "omnislam/lcmio/decode.h"
#include "omnislam/lcmio/image_msg.h"
#include "omnislam/lcmio/log_reader.h"
#include "omnislam/lcmio/validate.h"

namespace omnislam::fuzz {
namespace {

/// decode as Msg; when that succeeds, validate (a refused message goes no further).
template <class Msg>
std::optional<Msg> decodeAndValidate(const uint8_t* data, size_t size) {
  Msg m;
  if (lcmio::decode(data, size, m)) return std::nullopt;
  if (lcmio::validate(m)) return std::nullopt;
  return m;
}

/// What a receiver of an OMNI_IMAGE does with a valid message: decode its pixels (the headers of
/// JPEG and PNG checked first), as omnislam-features and omnislam-logstat do.
void decodePixels(const image_t& m) {
  std::string why;
  const auto img = lcmio::decodeImage(m, &why);
  if (img && img->empty()) reportUnexpected("lcm_messages", "empty image", "decodeImage gave an empty image");
}

/// Every type of the contract a receiver decodes (SLAM_HEALTH has no receiver yet); the fingerprint
/// in the first 8 bytes selects the one that can succeed.
void decodeAnyMessage(const uint8_t* data, size_t size) {
  if (auto m = decodeAndValidate<image_t>(data, size)) decodePixels(*m);
  decodeAndValidate<features_t>(data, size);
  decodeAndValidate<odometry_t>(data, size);
  decodeAndValidate<pose_t>(data, size);
  decodeAndValidate<map_t>(data, size);
  decodeAndValidate<particles_t>(data, size);
  decodeAndValidate<associations_t>(data, size);
  decodeAndValidate<feature_labels_t>(data, size);
  decodeAndValidate<process_status_t>(data, size);
  decodeAndValidate<slam_localisation_t>(data, size);  // omnislam-logstat decodes it (since 0.5)
}

}  // namespace

void fuzzLcmMessages(const uint8_t* data, size_t size) {
  guard<>("lcm_messages", [&] { decodeAnyMessage(data, size); });  // none of it throws
}

void fuzzLcmLog(const uint8_t* data, size_t size) {
  const std::string path = scratchFile("lcm_log", data, size);
  guard<>("lcm_log", [&] {  // the reader stops at a bad event; it throws only when it cannot open
    lcmio::LogReader in(path);
    lcmio::LogEvent ev;
    std::string why;
    while (in.next(ev)) {  // each event decoded by its channel, as the replay and the tools do
      if (ev.channel == channels::kOdometry) lcmio::decodeValid<odometry_t>(ev, &why);
      if (ev.channel == channels::kOmniFeatures) lcmio::decodeValid<features_t>(ev, &why);
      if (ev.channel == channels::kSlamPose) lcmio::decodeValid<pose_t>(ev, &why);
      if (ev.channel == channels::kSlamMap) lcmio::decodeValid<map_t>(ev, &why);
      if (ev.channel == channels::kGroundTruthPose) lcmio::decodeValid<pose_t>(ev, &why);
      if (ev.channel == channels::kProcessStatus) lcmio::decodeValid<process_status_t>(ev, &why);
    }
    (void)in.result().problem(path);
  });
}

}  // namespace omnislam::fuzz
