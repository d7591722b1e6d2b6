// Little-endian state encoding and its CRC-checked envelope: see byte_codec.h.
#include "omnislam/core/byte_codec.h"

#include <cstring>

namespace omnislam {

namespace {

constexpr std::size_t kHeaderBytes = 8 + 4 + 8;
constexpr std::size_t kTrailerBytes = 4;

std::array<std::uint32_t, 256> makeCrcTable() {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}

std::uint64_t loadLe(const std::uint8_t* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

std::string hex32(std::uint32_t v) {
  static const char* d = "0123456789abcdef";
  std::string s = "0x";
  for (int i = 28; i >= 0; i -= 4) s.push_back(d[(v >> i) & 0xFu]);
  return s;
}

}  // namespace

std::uint32_t crc32(const std::uint8_t* data, std::size_t n, std::uint32_t crc) {
  static const std::array<std::uint32_t, 256> table = makeCrcTable();
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) crc = table[(crc ^ data[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

// ---- ByteWriter -----------------------------------------------------------------------------

void ByteWriter::u32(std::uint32_t v) {
  for (int i = 0; i < 4; ++i) buf_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

void ByteWriter::u64(std::uint64_t v) {
  for (int i = 0; i < 8; ++i) buf_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

void ByteWriter::f32(float v) {
  std::uint32_t b;
  std::memcpy(&b, &v, sizeof b);
  u32(b);
}

void ByteWriter::f64(double v) {
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  u64(b);
}

void ByteWriter::str(const std::string& s) {
  u64(s.size());
  bytes(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
}

// ---- ByteReader -----------------------------------------------------------------------------

const std::uint8_t* ByteReader::take(std::size_t k, const char* what) {
  if (k > remaining())
    throw StateFormatError(std::string("truncated: ") + what + " needs " + std::to_string(k) + " bytes at offset " +
                           std::to_string(pos_) + ", " + std::to_string(remaining()) + " left");
  const std::uint8_t* p = p_ + pos_;
  pos_ += k;
  return p;
}

std::uint8_t ByteReader::u8(const char* what) { return *take(1, what); }

bool ByteReader::boolean(const char* what) {
  const std::uint8_t v = u8(what);
  if (v > 1) throw StateFormatError(std::string(what) + ": " + std::to_string(v) + " is not a boolean (0 or 1)");
  return v == 1;
}

std::uint32_t ByteReader::u32(const char* what) { return static_cast<std::uint32_t>(loadLe(take(4, what), 4)); }
std::uint64_t ByteReader::u64(const char* what) { return loadLe(take(8, what), 8); }

float ByteReader::f32(const char* what) {
  const std::uint32_t b = u32(what);
  float v;
  std::memcpy(&v, &b, sizeof v);
  return v;
}

double ByteReader::f64(const char* what) {
  const std::uint64_t b = u64(what);
  double v;
  std::memcpy(&v, &b, sizeof v);
  return v;
}

std::string ByteReader::str(const char* what, std::size_t max_size) {
  const std::size_t n = count(what, max_size, 1);
  const std::uint8_t* p = take(n, what);
  return std::string(reinterpret_cast<const char*>(p), n);
}

std::size_t ByteReader::count(const char* what, std::size_t max_count, std::size_t min_bytes_each) {
  const std::uint64_t n = u64(what);
  if (n > max_count)
    throw StateFormatError(std::string(what) + ": count " + std::to_string(n) + " is above the limit " +
                           std::to_string(max_count));
  if (min_bytes_each > 0 && n > remaining() / min_bytes_each)
    throw StateFormatError(std::string("truncated: ") + what + ": count " + std::to_string(n) + " needs at least " +
                           std::to_string(n * min_bytes_each) + " bytes, " + std::to_string(remaining()) + " left");
  return static_cast<std::size_t>(n);
}

void ByteReader::expectEnd(const char* what) const {
  if (remaining() != 0)
    throw StateFormatError(std::string(what) + ": " + std::to_string(remaining()) + " unread bytes at offset " +
                           std::to_string(pos_) + " (a format mismatch)");
}

// ---- envelope -------------------------------------------------------------------------------

std::vector<std::uint8_t> sealState(const StateMagic& magic, std::uint32_t version,
                                    const std::vector<std::uint8_t>& payload) {
  ByteWriter w;
  w.bytes(reinterpret_cast<const std::uint8_t*>(magic.data()), magic.size());
  w.u32(version);
  w.u64(payload.size());
  w.bytes(payload.data(), payload.size());
  const std::uint32_t crc = crc32(w.buffer().data(), w.size());
  w.u32(crc);
  return w.release();
}

OpenedState openState(const StateMagic& magic, std::uint32_t expected_version, const std::uint8_t* bytes,
                      std::size_t size) {
  if (size < kHeaderBytes + kTrailerBytes)
    throw StateFormatError("truncated: " + std::to_string(size) + " bytes, shorter than the " +
                           std::to_string(kHeaderBytes + kTrailerBytes) + "-byte header and checksum");
  if (std::memcmp(bytes, magic.data(), magic.size()) != 0)
    throw StateFormatError("wrong magic: not a '" + std::string(magic.data(), magic.size()) + "' file");
  OpenedState out;
  out.version = static_cast<std::uint32_t>(loadLe(bytes + 8, 4));
  if (out.version != expected_version)
    throw StateFormatError("format version " + std::to_string(out.version) + ", this program reads version " +
                           std::to_string(expected_version));
  const std::uint64_t payload = loadLe(bytes + 12, 8);
  const std::size_t have = size - kHeaderBytes - kTrailerBytes;
  if (payload != have)
    throw StateFormatError((payload > have ? "truncated: " : "trailing bytes: ") + std::string("the header says ") +
                           std::to_string(payload) + " payload bytes, the file holds " + std::to_string(have));
  const std::uint32_t stored = static_cast<std::uint32_t>(loadLe(bytes + size - kTrailerBytes, 4));
  const std::uint32_t computed = crc32(bytes, size - kTrailerBytes);
  if (stored != computed)
    throw StateFormatError("checksum mismatch: stored " + hex32(stored) + ", computed " + hex32(computed) +
                           " (a damaged byte)");
  out.payload.assign(bytes + kHeaderBytes, bytes + kHeaderBytes + have);
  return out;
}

}  // namespace omnislam
