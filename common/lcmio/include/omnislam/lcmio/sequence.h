// Sequence numbers of one input stream: how a message's seq relates to the previous one's, as a
// count of missed messages or a restart, without overflow for any pair of non-negative seqs.
// Used per channel by lcmio::Node (PROCESS_STATUS.sequence_gaps) and by omnislam-logstat.
#pragma once

#include <cstdint>

namespace omnislam::lcmio {

/// A seq more than this ahead of the previous one is not counted as that many missed messages:
/// it is a publisher's counter re-based or a corrupted field (a flipped high bit would otherwise
/// report some 1e18 lost messages). A million is over five hours of the fastest stream of the
/// contract (50 Hz).
inline constexpr int64_t kMaxSequenceGap = 1'000'000;

struct SequenceStep {
  int64_t missed = 0;    ///< messages missing between the previous seq and this one
  bool restart = false;  ///< seq not after the previous one, or more than max_gap ahead of it
};

/// The step from `last` to `seq` (both >= 0, as lcmio::validate guarantees).
SequenceStep sequenceStep(int64_t last, int64_t seq, int64_t max_gap = kMaxSequenceGap);

/// `total + add` for non-negative counters, held at INT64_MAX instead of overflowing.
int64_t saturatingAdd(int64_t total, int64_t add);

}  // namespace omnislam::lcmio
