// The landmark map as map_t (map_message.h).
#include "omnislam/runtime/map_message.h"

#include "omnislam/features_t.hpp"

namespace omnislam::runtime {

map_t toMapMessage(const std::vector<slam::Landmark>& landmarks, std::size_t num_candidates, std::int64_t utime,
                   std::int64_t seq, std::int64_t input_seq) {
  map_t m{};
  m.utime = utime;
  m.seq = seq;
  m.input_seq = input_seq;
  for (const slam::Landmark& L : landmarks) {
    landmark_t l{};
    l.id = static_cast<int64_t>(L.id);
    for (int i = 0; i < 3; ++i) {
      l.position_m[i] = L.p_LinW_m(i);
      for (int j = 0; j < 3; ++j) l.covariance[i][j] = L.cov_LinW_m2(i, j);
    }
    l.type = static_cast<int8_t>(L.type == slam::LandmarkType::kTypeI ? 1 : 2);
    l.times_detected = L.counter;
    l.kind =
        L.kind == slam::LandmarkKind::kVerticalLine ? feature_t::KIND_VERTICAL_LINE : feature_t::KIND_CEILING_LIGHT;
    m.landmarks.push_back(l);
  }
  m.num_landmarks = static_cast<int32_t>(m.landmarks.size());
  m.num_candidates = static_cast<int32_t>(num_candidates);
  return m;
}

}  // namespace omnislam::runtime
