// How much of a run the SLAM output covers: the share of the feature frames it answered (a pose at
// the frame's utime) and the share of the reference span its poses cover (the frames' span, or the
// truth's when there are no frames). A run below either minimum is incomplete: its figures (ATE,
// map) describe only part of it. Utimes in microseconds in, spans and gaps in seconds out. Pure.
#pragma once

#include <cstdint>
#include <vector>

namespace omnislam::eval {

/// The minimum shares below which a run is incomplete (omnislam-eval --min-answered, --min-span).
struct CoverageOptions {
  double min_answered_share = 0.9;  ///< answered frames / frames, in [0, 1]
  double min_span_share = 0.9;      ///< reference span covered by the poses / reference span, in [0, 1]
};

struct Coverage {
  int64_t frames = 0;                ///< distinct feature-frame utimes (0: none, nothing to answer)
  int64_t frames_answered = 0;       ///< of them, those with a pose at the same utime
  double answered_share = 1.0;       ///< frames_answered / frames; 1 when frames == 0
  bool reference_is_frames = false;  ///< the reference span is the frames' (else the truth's)
  double reference_span_s = 0.0;     ///< last - first utime of the reference
  double pose_span_s = 0.0;          ///< last - first pose utime
  double start_gap_s = 0.0;          ///< first pose - reference start (> 0: the poses start late)
  double end_gap_s = 0.0;            ///< reference end - last pose (> 0: the poses end early)
  double span_share = 0.0;           ///< overlap of [first, last pose] with the reference span / that span
  double truth_span_s = 0.0;         ///< last - first truth utime (0 without truth)
  double truth_end_gap_s = 0.0;      ///< last truth - last pose (> 0: the poses end before the truth)
  bool answered_ok = true;           ///< answered_share >= min_answered_share
  bool span_ok = true;               ///< span_share >= min_span_share
  bool complete() const { return answered_ok && span_ok; }
};

/// The coverage of `pose_utimes` (SLAM_POSE) over `frame_utimes` (OMNI_FEATURES; repeated utimes
/// count once) and `truth_utimes` (GROUND_TRUTH_POSE). Any order. Without poses nothing is covered
/// (shares 0); without frames the answered share is 1 and the truth is the reference; without
/// frames and truth the span share is 1 (nothing to cover). A reference of one instant is covered
/// (share 1) when the poses reach from before it to after it, else not (0).
Coverage coverage(std::vector<int64_t> frame_utimes, std::vector<int64_t> pose_utimes,
                  const std::vector<int64_t>& truth_utimes, const CoverageOptions& opt);

}  // namespace omnislam::eval
