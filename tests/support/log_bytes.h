// Test support: one event in lcm-logger's file format built byte by byte, so a test can write logs
// with damaged lengths, event numbers or channels that no LCM writer would produce.
#pragma once

#include <cstdint>
#include <string>

namespace omnislam::testing {

/// The 28-byte header (sync word, event number, utime 1 s, channel and data lengths, big-endian)
/// followed by `channel` and `data`. A declared length < 0 is the true one; any other value is
/// written as it is, whatever the bytes that follow.
inline std::string rawLogEvent(int64_t number, const std::string& channel, const std::string& data,
                               int64_t declared_data = -1, int64_t declared_channel = -1) {
  auto be = [](uint64_t v, int n) {
    std::string b;
    for (int i = n - 1; i >= 0; --i) b.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
    return b;
  };
  return be(0xEDA1DA01u, 4) + be(static_cast<uint64_t>(number), 8) + be(1'000'000, 8) +
         be(static_cast<uint64_t>(declared_channel >= 0 ? declared_channel : static_cast<int64_t>(channel.size())), 4) +
         be(static_cast<uint64_t>(declared_data >= 0 ? declared_data : static_cast<int64_t>(data.size())), 4) +
         channel + data;
}

}  // namespace omnislam::testing
