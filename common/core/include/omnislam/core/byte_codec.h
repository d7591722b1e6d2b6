// Binary encoding for state that must survive its process (SLAM checkpoints): little-endian
// integers, doubles as their IEEE-754 bit patterns (a round trip is bit-exact), length-prefixed
// strings, every read bounds-checked; and a sealed envelope: 8-byte magic, format version, payload
// size, payload, CRC-32 of all that. Pure code (memory buffers only, no files).
//
// Envelope layout (all integers little-endian):
//   magic[8] | u32 version | u64 payload_size | payload[payload_size] | u32 crc32(everything before)
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace omnislam {

/// A state buffer that cannot be read: truncated, a wrong magic or version, a checksum mismatch, a
/// size out of range or an inconsistent value. what() is one line giving the reason.
class StateFormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320) of `n` bytes, continuing `crc` (0 to start).
std::uint32_t crc32(const std::uint8_t* data, std::size_t n, std::uint32_t crc = 0);

/// Appends values to a byte buffer.
class ByteWriter {
 public:
  void u8(std::uint8_t v) { buf_.push_back(v); }
  void boolean(bool v) { u8(v ? 1 : 0); }
  void u32(std::uint32_t v);
  void u64(std::uint64_t v);
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f32(float v);
  void f64(double v);
  /// A u64 count followed by the bytes.
  void str(const std::string& s);
  void bytes(const std::uint8_t* p, std::size_t n) { buf_.insert(buf_.end(), p, p + n); }
  const std::vector<std::uint8_t>& buffer() const { return buf_; }
  std::vector<std::uint8_t> release() { return std::move(buf_); }
  std::size_t size() const { return buf_.size(); }

 private:
  std::vector<std::uint8_t> buf_;
};

/// Reads values back in the order written; every read past the end, and every count that the
/// remaining bytes cannot hold, throws StateFormatError naming what was being read.
class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : p_(data), n_(size) {}
  explicit ByteReader(const std::vector<std::uint8_t>& v) : ByteReader(v.data(), v.size()) {}

  std::uint8_t u8(const char* what);
  bool boolean(const char* what);  ///< 0 or 1, anything else throws
  std::uint32_t u32(const char* what);
  std::uint64_t u64(const char* what);
  std::int32_t i32(const char* what) { return static_cast<std::int32_t>(u32(what)); }
  std::int64_t i64(const char* what) { return static_cast<std::int64_t>(u64(what)); }
  float f32(const char* what);
  double f64(const char* what);
  std::string str(const char* what, std::size_t max_size);
  /// A u64 element count, at most max_count and at most remaining() / min_bytes_each (a count
  /// that the rest of the buffer cannot hold is refused before anything is allocated).
  std::size_t count(const char* what, std::size_t max_count, std::size_t min_bytes_each);
  std::size_t remaining() const { return n_ - pos_; }
  std::size_t offset() const { return pos_; }
  /// Throws unless every byte has been read (trailing bytes mean a format mismatch).
  void expectEnd(const char* what) const;

 private:
  const std::uint8_t* take(std::size_t k, const char* what);
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
};

using StateMagic = std::array<char, 8>;

/// The envelope around `payload` (layout above).
std::vector<std::uint8_t> sealState(const StateMagic& magic, std::uint32_t version,
                                    const std::vector<std::uint8_t>& payload);

/// What openState() found.
struct OpenedState {
  std::uint32_t version = 0;
  std::vector<std::uint8_t> payload;
};

/// Checks the envelope of `bytes` and returns its payload. Throws StateFormatError with the reason:
/// shorter than a header, another magic (not this kind of file), a version other than
/// `expected_version`, a size that disagrees with the buffer (truncated or trailing bytes), or a
/// checksum mismatch (a flipped or damaged byte).
OpenedState openState(const StateMagic& magic, std::uint32_t expected_version, const std::uint8_t* bytes,
                      std::size_t size);

}  // namespace omnislam
