// The coverage of a run by the SLAM output (coverage.h): answered frames and covered span.
#include "omnislam/eval/coverage.h"

#include <algorithm>

namespace omnislam::eval {

namespace {

constexpr double kSecondsPerUs = 1e-6;

void sortUnique(std::vector<int64_t>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

/// The share of [ref_first, ref_last] inside [first, last]: 1 for an instant inside it.
double spanShare(int64_t first, int64_t last, int64_t ref_first, int64_t ref_last) {
  const int64_t lo = std::max(first, ref_first), hi = std::min(last, ref_last);
  if (ref_last == ref_first) return first <= ref_first && last >= ref_last ? 1.0 : 0.0;
  if (hi <= lo) return 0.0;
  return static_cast<double>(hi - lo) / static_cast<double>(ref_last - ref_first);
}

}  // namespace

Coverage coverage(std::vector<int64_t> frame_utimes, std::vector<int64_t> pose_utimes,
                  const std::vector<int64_t>& truth_utimes, const CoverageOptions& opt) {
  Coverage c;
  sortUnique(frame_utimes);
  sortUnique(pose_utimes);
  c.frames = static_cast<int64_t>(frame_utimes.size());
  for (int64_t u : frame_utimes)
    c.frames_answered += std::binary_search(pose_utimes.begin(), pose_utimes.end(), u) ? 1 : 0;
  if (c.frames > 0) c.answered_share = static_cast<double>(c.frames_answered) / static_cast<double>(c.frames);
  int64_t truth_first = 0, truth_last = 0;
  if (!truth_utimes.empty()) {
    const auto [lo, hi] = std::minmax_element(truth_utimes.begin(), truth_utimes.end());
    truth_first = *lo, truth_last = *hi;
    c.truth_span_s = (truth_last - truth_first) * kSecondsPerUs;
  }
  c.reference_is_frames = !frame_utimes.empty();
  const bool have_reference = c.reference_is_frames || !truth_utimes.empty();
  const int64_t ref_first = c.reference_is_frames ? frame_utimes.front() : truth_first;
  const int64_t ref_last = c.reference_is_frames ? frame_utimes.back() : truth_last;
  c.reference_span_s = (ref_last - ref_first) * kSecondsPerUs;
  if (pose_utimes.empty()) {
    c.span_share = have_reference ? 0.0 : 1.0;
  } else {
    const int64_t first = pose_utimes.front(), last = pose_utimes.back();
    c.pose_span_s = (last - first) * kSecondsPerUs;
    c.span_share = have_reference ? spanShare(first, last, ref_first, ref_last) : 1.0;
    if (have_reference) {
      c.start_gap_s = (first - ref_first) * kSecondsPerUs;
      c.end_gap_s = (ref_last - last) * kSecondsPerUs;
    }
    if (!truth_utimes.empty()) c.truth_end_gap_s = (truth_last - last) * kSecondsPerUs;
  }
  c.answered_ok = c.answered_share >= opt.min_answered_share;
  c.span_ok = c.span_share >= opt.min_span_share;
  return c;
}

}  // namespace omnislam::eval
