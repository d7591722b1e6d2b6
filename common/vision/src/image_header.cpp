// Headers of encoded images read without decoding them: see image_header.h. Every read is bounds
// checked against the byte count; nothing here throws or allocates beyond the result strings.
#include "omnislam/vision/image_header.h"

#include <cstring>

namespace omnislam::vision {
namespace {

/// A side above this is refused as malformed: no decoder used here handles one, and it keeps every
/// product of the header's figures (pixels x channels x bytes) far inside int64.
constexpr int64_t kMaxSidePx = int64_t{1} << 24;

uint32_t bigEndian(const uint8_t* p, int bytes) {
  uint32_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

uint32_t littleEndian(const uint8_t* p, int bytes) {
  uint32_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

HeaderResult fail(std::string why) { return HeaderResult{std::nullopt, std::move(why)}; }

std::string at(size_t i) { return " at byte " + std::to_string(i); }

std::optional<std::string> sidesProblem(const char* codec, int64_t w, int64_t h) {
  if (w >= 1 && h >= 1 && w <= kMaxSidePx && h <= kMaxSidePx) return std::nullopt;
  return std::string(codec) + " header claims " + std::to_string(w) + "x" + std::to_string(h) +
         " px: a side outside 1..2^24";
}

// ---------------------------------------------------------------- PNG
constexpr uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

/// Walks the chunks after the signature until a whole chunk of type `stop` (true) or the end of the
/// data, a chunk that does not fit or IEND (false). *where: the offset of the chunk it stopped at.
bool findPngChunk(const uint8_t* d, size_t n, const char* stop, size_t* where) {
  size_t i = 8;
  while (i + 8 <= n) {
    const uint32_t len = bigEndian(d + i, 4);
    *where = i;
    if (len > 0x7fffffffu || len + size_t{12} > n - i) return false;  // the chunk does not fit
    if (std::memcmp(d + i + 4, stop, 4) == 0) return true;
    if (std::memcmp(d + i + 4, "IEND", 4) == 0) return false;
    i += len + size_t{12};  // length, type, data, CRC
  }
  *where = i;
  return false;
}

bool validPngDepth(int type, int depth) {
  switch (type) {
    case 0: return depth == 1 || depth == 2 || depth == 4 || depth == 8 || depth == 16;
    case 3: return depth == 1 || depth == 2 || depth == 4 || depth == 8;
    case 2:
    case 4:
    case 6: return depth == 8 || depth == 16;
    default: return false;
  }
}

HeaderResult readPng(const uint8_t* d, size_t n) {
  if (n < 33) return fail("PNG of " + std::to_string(n) + " bytes: shorter than its signature and IHDR chunk");
  if (bigEndian(d + 8, 4) != 13 || std::memcmp(d + 12, "IHDR", 4) != 0) return fail("PNG without an IHDR chunk first");
  ImageHeader h;
  h.codec = ImageCodec::kPng;
  h.width_px = bigEndian(d + 16, 4);
  h.height_px = bigEndian(d + 20, 4);
  if (auto why = sidesProblem("PNG", h.width_px, h.height_px)) return fail(*why);
  const int depth = d[24], type = d[25];
  if (!validPngDepth(type, depth))
    return fail("PNG colour type " + std::to_string(type) + " with bit depth " + std::to_string(depth) + ": not valid");
  if (d[26] != 0 || d[27] != 0 || d[28] > 1) return fail("PNG with an unknown compression, filter or interlace method");
  h.bit_depth = depth;
  h.channels = type == 0 ? 1 : (type == 4 || type == 6) ? 4 : 3;
  if (type == 2 || type == 3) {  // OpenCV adds alpha for a tRNS chunk (it comes before IDAT)
    size_t where = 0;
    if (findPngChunk(d, n, "tRNS", &where)) {
      size_t idat = 0;
      if (!findPngChunk(d, n, "IDAT", &idat) || where < idat) h.channels = 4;
    }
  }
  return HeaderResult{h, {}};
}

std::optional<std::string> pngComplete(const uint8_t* d, size_t n) {
  size_t where = 0;
  if (findPngChunk(d, n, "IEND", &where)) return std::nullopt;
  if (where + 8 <= n) {
    std::string type(reinterpret_cast<const char*>(d + where + 4), 4);
    for (char& c : type) c = (c >= 32 && c < 127) ? c : '?';
    return "truncated PNG: chunk '" + type + "'" + at(where) + " declares " + std::to_string(bigEndian(d + where, 4)) +
           " bytes, " + std::to_string(n - where - 8) + " are left (no complete IEND chunk)";
  }
  return "truncated PNG: the data ends after " + std::to_string(n) + " bytes without an IEND chunk";
}

// ---------------------------------------------------------------- JPEG
bool isStandaloneMarker(uint8_t m) { return m == 0x01 || (m >= 0xD0 && m <= 0xD7); }
// SOF0..SOF15 except DHT (C4), JPG (C8) and DAC (CC).
bool isFrameMarker(uint8_t m) { return m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC; }

std::string hex(uint8_t m) {
  static const char* digits = "0123456789ABCDEF";
  return std::string("0xFF") + digits[m >> 4] + digits[m & 15];
}

/// Moves *i from a marker's 0xFF over fill bytes to the marker code; false at the end of the data.
bool nextMarker(const uint8_t* d, size_t n, size_t* i, uint8_t* marker) {
  while (*i < n && d[*i] == 0xFF) ++*i;
  if (*i >= n) return false;
  *marker = d[(*i)++];
  return true;
}

HeaderResult frameHeader(const uint8_t* d, size_t n, size_t i, uint8_t m) {
  const uint32_t len = bigEndian(d + i, 2);
  if (len < 8 || i + len > n) return fail("JPEG frame header" + at(i) + " truncated");
  ImageHeader h;
  h.codec = ImageCodec::kJpeg;
  h.bit_depth = d[i + 2];
  h.height_px = bigEndian(d + i + 3, 2);
  h.width_px = bigEndian(d + i + 5, 2);
  const int components = d[i + 7];
  h.progressive = m == 0xC2 || m == 0xC6 || m == 0xCA || m == 0xCE;
  if (h.height_px == 0) return fail("JPEG height 0 (a DNL-defined height, which libjpeg does not support)");
  if (auto why = sidesProblem("JPEG", h.width_px, h.height_px)) return fail(*why);
  if (h.bit_depth < 2 || h.bit_depth > 16)
    return fail("JPEG sample precision " + std::to_string(h.bit_depth) + " bits");
  if (components != 1 && components != 3 && components != 4)
    return fail("JPEG with " + std::to_string(components) + " components (1, 3 or 4 are decoded)");
  if (len < 8u + 3u * static_cast<uint32_t>(components)) return fail("JPEG frame header" + at(i) + " too short");
  h.channels = components == 1 ? 1 : 3;
  return HeaderResult{h, {}};
}

HeaderResult readJpeg(const uint8_t* d, size_t n) {
  size_t i = 2;
  while (true) {
    if (i >= n) return fail("JPEG ends after " + std::to_string(n) + " bytes, before its frame header");
    if (d[i] != 0xFF) return fail("JPEG: no marker" + at(i) + " where a segment must start");
    uint8_t m = 0;
    if (!nextMarker(d, n, &i, &m)) return fail("JPEG ends in fill bytes before its frame header");
    if (isStandaloneMarker(m)) continue;
    if (m == 0x00 || m == 0xD8 || m == 0xD9 || m == 0xDA)
      return fail("JPEG: marker " + hex(m) + at(i - 1) + " before any frame header");
    if (i + 2 > n) return fail("JPEG ends inside the length of marker " + hex(m));
    const uint32_t len = bigEndian(d + i, 2);
    if (len < 2) return fail("JPEG: segment " + hex(m) + at(i) + " with length " + std::to_string(len));
    if (isFrameMarker(m)) return frameHeader(d, n, i, m);
    i += len;
  }
}

/// Skips the entropy-coded data of a scan starting at *i, to the 0xFF of the next marker other
/// than RSTn (0xFF 0x00 is a stuffed data byte). False when the data ends first.
bool skipEntropyCoded(const uint8_t* d, size_t n, size_t* i) {
  while (*i < n) {
    const void* ff = std::memchr(d + *i, 0xFF, n - *i);
    if (ff == nullptr) return false;
    *i = static_cast<size_t>(static_cast<const uint8_t*>(ff) - d);
    if (*i + 1 >= n) return false;
    const uint8_t b = d[*i + 1];
    if (b == 0x00 || (b >= 0xD0 && b <= 0xD7)) *i += 2;
    else if (b == 0xFF) *i += 1;  // a fill byte before a marker
    else return true;
  }
  return false;
}

std::optional<std::string> jpegComplete(const uint8_t* d, size_t n) {
  const std::string truncated = "truncated JPEG: no end-of-image marker (EOI) in its " + std::to_string(n) + " bytes";
  size_t i = 2;
  int scans = 0;
  bool frame = false;
  while (true) {
    if (i >= n) return truncated;
    if (d[i] != 0xFF) return "corrupt JPEG: no marker" + at(i) + " where a segment must start";
    uint8_t m = 0;
    if (!nextMarker(d, n, &i, &m)) return truncated;
    if (m == 0xD9) {
      if (scans == 0) return std::string("JPEG without image data: end-of-image marker before any scan");
      return std::nullopt;
    }
    if (isStandaloneMarker(m)) continue;
    if (m == 0x00 || m == 0xD8) return "corrupt JPEG: marker " + hex(m) + at(i - 1);
    if (i + 2 > n) return truncated;
    const uint32_t len = bigEndian(d + i, 2);
    if (len < 2) return "corrupt JPEG: segment " + hex(m) + at(i) + " with length " + std::to_string(len);
    if (i + len > n) return truncated + "; the data ends inside segment " + hex(m) + at(i);
    frame = frame || isFrameMarker(m);
    i += len;
    if (m != 0xDA) continue;
    if (!frame) return std::string("corrupt JPEG: a scan before the frame header");
    ++scans;
    if (!skipEntropyCoded(d, n, &i)) return truncated + "; the data ends inside scan " + std::to_string(scans);
  }
}

// ---------------------------------------------------------------- BMP
bool bmpPaletteIsGrey(const uint8_t* d, size_t at_byte, int64_t entries, int entry_bytes) {
  for (int64_t k = 0; k < entries; ++k) {
    const size_t p = at_byte + static_cast<size_t>(k * entry_bytes);
    if (d[p] != d[p + 1] || d[p] != d[p + 2]) return false;
  }
  return true;
}

HeaderResult readBmp(const uint8_t* d, size_t n) {
  if (n < 26) return fail("BMP of " + std::to_string(n) + " bytes: shorter than its headers");
  const uint32_t offset = littleEndian(d + 10, 4), info = littleEndian(d + 14, 4);
  ImageHeader h;
  h.codec = ImageCodec::kBmp;
  h.bit_depth = 8;
  int bpp = 0, entry_bytes = 3;
  uint32_t compression = 0, colours_used = 0;
  if (info == 12) {  // BITMAPCOREHEADER (OS/2 1.x)
    h.width_px = littleEndian(d + 18, 2);
    h.height_px = littleEndian(d + 20, 2);
    bpp = static_cast<int>(littleEndian(d + 24, 2));
  } else if (info == 40 || info == 52 || info == 56 || info == 64 || info == 108 || info == 124) {
    if (n < 54) return fail("BMP info header truncated");
    h.width_px = static_cast<int32_t>(littleEndian(d + 18, 4));
    const int64_t signed_height = static_cast<int32_t>(littleEndian(d + 22, 4));
    h.height_px = signed_height < 0 ? -signed_height : signed_height;  // negative: rows top-down
    bpp = static_cast<int>(littleEndian(d + 28, 2));
    compression = littleEndian(d + 30, 4);
    colours_used = littleEndian(d + 46, 4);
    entry_bytes = 4;
  } else {
    return fail("BMP info header of " + std::to_string(info) + " bytes: not a known version");
  }
  if (auto why = sidesProblem("BMP", h.width_px, h.height_px)) return fail(*why);
  const bool rle = (compression == 1 && bpp == 8) || (compression == 2 && bpp == 4);
  const bool fields = compression == 3 && (bpp == 16 || bpp == 32);
  if (bpp != 1 && bpp != 4 && bpp != 8 && bpp != 16 && bpp != 24 && bpp != 32)
    return fail("BMP with " + std::to_string(bpp) + " bits per pixel");
  if (compression != 0 && !rle && !fields)
    return fail("BMP compression " + std::to_string(compression) + " with " + std::to_string(bpp) + " bits per pixel");
  if (bpp > 8) {
    h.channels = bpp == 32 && fields ? 4 : 3;
  } else {
    const int64_t full = int64_t{1} << bpp;
    const int64_t entries = colours_used == 0 || colours_used > full ? full : colours_used;
    const size_t palette = 14 + static_cast<size_t>(info);
    if (palette + static_cast<size_t>(entries * entry_bytes) > n) return fail("BMP palette truncated");
    h.channels = bmpPaletteIsGrey(d, palette, entries, entry_bytes) ? 1 : 3;
  }
  if (!rle) h.raster_end_bytes = offset + (h.width_px * bpp + 31) / 32 * 4 * h.height_px;
  return HeaderResult{h, {}};
}

// ---------------------------------------------------------------- PGM / PPM / PBM
/// The next decimal number after whitespace and '#' comments; false if there is none before the
/// end of the data or it exceeds 2^31 - 1.
bool pnmNumber(const uint8_t* d, size_t n, size_t* i, int64_t* value) {
  while (*i < n) {
    if (d[*i] == '#') {
      while (*i < n && d[*i] != '\n' && d[*i] != '\r') ++*i;
    } else if (d[*i] == ' ' || d[*i] == '\t' || d[*i] == '\n' || d[*i] == '\r' || d[*i] == '\v' || d[*i] == '\f') {
      ++*i;
    } else {
      break;
    }
  }
  if (*i >= n || d[*i] < '0' || d[*i] > '9') return false;
  *value = 0;
  while (*i < n && d[*i] >= '0' && d[*i] <= '9') {
    *value = *value * 10 + (d[*i] - '0');
    if (*value > 0x7fffffff) return false;
    ++*i;
  }
  return *i < n;  // a number must be followed by at least one whitespace byte
}

HeaderResult readPnm(const uint8_t* d, size_t n) {
  const char kind = static_cast<char>(d[1]);
  const bool bitmap = kind == '1' || kind == '4';
  const bool binary = kind >= '4';
  ImageHeader h;
  h.codec = ImageCodec::kPnm;
  size_t i = 2;
  int64_t maxval = 1;
  if (!pnmNumber(d, n, &i, &h.width_px) || !pnmNumber(d, n, &i, &h.height_px) ||
      (!bitmap && !pnmNumber(d, n, &i, &maxval)))
    return fail(std::string("P") + kind + " header truncated or not a number where width, height or maxval must be");
  if (auto why = sidesProblem("PNM", h.width_px, h.height_px)) return fail(*why);
  if (maxval < 1 || maxval > 65535) return fail("PNM maxval " + std::to_string(maxval) + " outside 1..65535");
  h.channels = kind == '3' || kind == '6' ? 3 : 1;
  h.bit_depth = bitmap ? 1 : maxval > 255 ? 16 : 8;
  const int64_t data_at = static_cast<int64_t>(i) + 1;  // one whitespace byte ends the header
  if (kind == '4') h.raster_end_bytes = data_at + (h.width_px + 7) / 8 * h.height_px;
  else if (binary) h.raster_end_bytes = data_at + h.pixels() * h.channels * h.bytesPerChannel();
  return HeaderResult{h, {}};
}

}  // namespace

const char* codecName(ImageCodec codec) {
  switch (codec) {
    case ImageCodec::kPng: return "PNG";
    case ImageCodec::kJpeg: return "JPEG";
    case ImageCodec::kBmp: return "BMP";
    case ImageCodec::kPnm: return "PNM";
  }
  return "?";
}

std::string ImageHeader::describe() const {
  return std::to_string(width_px) + "x" + std::to_string(height_px) + ", " + std::to_string(channels) +
         (channels == 1 ? " channel, " : " channels, ") + std::to_string(bit_depth) + "-bit " + codecName(codec);
}

HeaderResult readImageHeader(const uint8_t* d, size_t n) {
  if (d == nullptr || n < 4) return fail("image of " + std::to_string(d == nullptr ? 0 : n) + " bytes: no header");
  if (n >= 8 && std::memcmp(d, kPngSignature, 8) == 0) return readPng(d, n);
  if (d[0] == 0xFF && d[1] == 0xD8 && d[2] == 0xFF) return readJpeg(d, n);
  if (d[0] == 'B' && d[1] == 'M') return readBmp(d, n);
  if (d[0] == 'P' && d[1] >= '1' && d[1] <= '6') return readPnm(d, n);
  return fail("not a PNG, JPEG, BMP or PGM/PPM/PBM image (unknown signature)");
}

std::optional<std::string> checkComplete(const ImageHeader& h, const uint8_t* d, size_t n) {
  switch (h.codec) {
    case ImageCodec::kPng: return pngComplete(d, n);
    case ImageCodec::kJpeg: return jpegComplete(d, n);
    case ImageCodec::kBmp:
    case ImageCodec::kPnm:
      if (h.raster_end_bytes > static_cast<int64_t>(n))
        return std::string("truncated ") + codecName(h.codec) + ": its pixels need " +
               std::to_string(h.raster_end_bytes) + " bytes, the data has " + std::to_string(n);
      return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace omnislam::vision
