// Sequence numbers of one input stream: see sequence.h.
#include "omnislam/lcmio/sequence.h"

#include <limits>

namespace omnislam::lcmio {

SequenceStep sequenceStep(int64_t last, int64_t seq, int64_t max_gap) {
  SequenceStep s;
  if (seq <= last) {
    s.restart = true;
  } else {
    const int64_t missed = seq - last - 1;  // no overflow: 0 <= last < seq
    if (missed > max_gap) s.restart = true;
    else s.missed = missed;
  }
  return s;
}

int64_t saturatingAdd(int64_t total, int64_t add) {
  constexpr int64_t kMax = std::numeric_limits<int64_t>::max();
  return add > kMax - total ? kMax : total + add;
}

}  // namespace omnislam::lcmio
