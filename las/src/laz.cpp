#include "geoanchor/las/laz.hpp"

#include <cstring>

#include "geoanchor/base/error.hpp"
#include "geoanchor/las/las.hpp"
#include "las_internal.hpp"
#include "laz_chunk.hpp"
#include "laz_entropy.hpp"
#include "laz_layout.hpp"

namespace geoanchor::io {
namespace {

using las_internal::get;

constexpr std::size_t kVlrFixedBytes = 34;
constexpr std::size_t kItemBytes = 6;

// Appends v's little-endian bytes one by one (GCC 12 reports false
// overflows on a ranged insert or a memcpy into a vector here).
template <class T>
void put(std::vector<std::uint8_t>& b, T v) {
  std::uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, &v, sizeof v);
  for (const std::uint8_t x : bytes) b.push_back(x);
}

Error unsupported(const std::string& where, const std::string& what) {
  return Error(ErrorKind::input, "E_LAZ_UNSUPPORTED", where + ": " + what);
}
Error bad_vlr(const std::string& where, const std::string& what) {
  return Error(ErrorKind::input, "E_LAZ_VLR", where + ": laszip VLR: " + what);
}

std::string describe(const LazItem& i) {
  return laz_item_name(i.type) + " (" + std::to_string(i.size) + " bytes, version " + std::to_string(i.version) + ")";
}
std::string describe(const std::vector<LazItem>& items) {
  std::string s;
  for (const auto& i : items) s += (s.empty() ? "" : ", ") + describe(i);
  return s;
}

// The record bytes the items cover.
std::uint16_t items_size(const LazVlr& vlr) {
  std::uint16_t size = 0;
  for (const auto& item : vlr.items) size = static_cast<std::uint16_t>(size + item.size);
  return size;
}

}  // namespace

laz::ChunkLayout chunk_layout(const LazVlr& vlr, std::uint16_t record_length) {
  laz::ChunkLayout l;
  l.layered = vlr.compressor == 3;
  l.record_length = record_length;
  for (const auto& item : vlr.items) {
    switch (static_cast<LazItemType>(item.type)) {
      case LazItemType::gpstime11: l.gps_time = true; break;
      case LazItemType::rgb12:
      case LazItemType::rgb14: l.rgb = true; break;
      case LazItemType::rgbnir14: l.rgb = l.nir = true; break;
      case LazItemType::byte:
      case LazItemType::byte14: l.extra_bytes = item.size; break;
      default: break;
    }
  }
  return l;
}

std::string laz_item_name(std::uint16_t type) {
  switch (type) {
    case 0: return "BYTE";
    case 1: return "SHORT";
    case 2: return "INT";
    case 3: return "LONG";
    case 4: return "FLOAT";
    case 5: return "DOUBLE";
    case 6: return "POINT10";
    case 7: return "GPSTIME11";
    case 8: return "RGB12";
    case 9: return "WAVEPACKET13";
    case 10: return "POINT14";
    case 11: return "RGB14";
    case 12: return "RGBNIR14";
    case 13: return "WAVEPACKET14";
    case 14: return "BYTE14";
    default: return "item type " + std::to_string(type);
  }
}

std::vector<std::uint8_t> LazVlr::bytes() const {
  std::vector<std::uint8_t> b;
  b.reserve(kVlrFixedBytes + kItemBytes * items.size());
  put(b, compressor);
  put(b, coder);
  put(b, version_major);
  put(b, version_minor);
  put(b, version_revision);
  put(b, options);
  put(b, chunk_size);
  put(b, special_evlr_count);
  put(b, special_evlr_offset);
  put(b, static_cast<std::uint16_t>(items.size()));
  for (const auto& i : items) {
    put(b, i.type);
    put(b, i.size);
    put(b, i.version);
  }
  return b;
}

LazVlr LazVlr::parse(const std::vector<std::uint8_t>& payload, const std::string& where) {
  if (payload.size() < kVlrFixedBytes) {
    throw bad_vlr(where, "holds " + std::to_string(payload.size()) + " bytes, fewer than the " +
                             std::to_string(kVlrFixedBytes) + " of its fixed fields");
  }
  const std::uint8_t* p = payload.data();
  LazVlr v;
  v.compressor = get<std::uint16_t>(p);
  v.coder = get<std::uint16_t>(p + 2);
  v.version_major = p[4];
  v.version_minor = p[5];
  v.version_revision = get<std::uint16_t>(p + 6);
  v.options = get<std::uint32_t>(p + 8);
  v.chunk_size = get<std::uint32_t>(p + 12);
  v.special_evlr_count = get<std::int64_t>(p + 16);
  v.special_evlr_offset = get<std::int64_t>(p + 24);
  const std::size_t count = get<std::uint16_t>(p + 32);
  if (payload.size() != kVlrFixedBytes + kItemBytes * count) {
    throw bad_vlr(where, "lists " + std::to_string(count) + " items, which take " +
                             std::to_string(kVlrFixedBytes + kItemBytes * count) + " bytes, but holds " +
                             std::to_string(payload.size()));
  }
  for (std::size_t k = 0; k < count; ++k) {
    const std::uint8_t* q = p + kVlrFixedBytes + kItemBytes * k;
    v.items.push_back({get<std::uint16_t>(q), get<std::uint16_t>(q + 2), get<std::uint16_t>(q + 4)});
  }
  return v;
}

LazVlr LazVlr::for_format(std::uint8_t point_format, std::uint16_t record_length, std::uint32_t chunk_points) {
  const std::string where = "LAZ output";
  const std::size_t base = las_min_record_length(point_format);
  if (base == 0) {
    const bool waveform = point_format == 4 || point_format == 5 || point_format == 9 || point_format == 10;
    throw unsupported(where, "point format " + std::to_string(point_format) +
                                 (waveform ? std::string(" carries waveform packets (") +
                                                 (point_format < 6 ? "WAVEPACKET13" : "WAVEPACKET14") +
                                                 "), which geoanchor does not compress; formats 0-3 and 6-8 are supported"
                                           : std::string(" is not a LAS point format")));
  }
  if (record_length < base) {
    throw bad_vlr(where, "record length " + std::to_string(record_length) + " is shorter than point format " +
                             std::to_string(point_format) + "'s " + std::to_string(base) + " bytes");
  }
  if (chunk_points == 0) throw bad_vlr(where, "a chunk of 0 points");
  LazVlr v;
  v.chunk_size = chunk_points;
  const auto extra = static_cast<std::uint16_t>(record_length - base);
  if (point_format < 6) {
    v.compressor = 2;
    v.items.push_back({6, 20, 2});
    if (point_format == 1 || point_format == 3) v.items.push_back({7, 8, 2});
    if (point_format == 2 || point_format == 3) v.items.push_back({8, 6, 2});
    if (extra) v.items.push_back({0, extra, 2});
  } else {
    v.compressor = 3;
    v.items.push_back({10, 30, 3});
    if (point_format == 7) v.items.push_back({11, 6, 3});
    if (point_format == 8) v.items.push_back({12, 8, 3});
    if (extra) v.items.push_back({14, extra, 3});
  }
  return v;
}

void LazVlr::check(std::uint8_t point_format, std::uint16_t record_length, const std::string& where) const {
  if (coder != 0) throw unsupported(where, "laszip VLR: coder " + std::to_string(coder) + " is not supported; 0 (arithmetic) is the only one");
  for (const auto& i : items) {
    if (i.type == 9 || i.type == 13) {
      throw unsupported(where, "laszip VLR: item " + describe(i) + " (waveform packets) is not supported");
    }
  }
  const std::size_t base = las_min_record_length(point_format);
  if (base == 0) {
    throw unsupported(where, "LAZ point format " + std::to_string(point_format) +
                                 " is not supported; formats 0-3 and 6-8 are");
  }
  const std::uint16_t wanted = point_format < 6 ? 2 : 3;
  if (compressor != wanted) {
    const char* names[] = {"none", "pointwise (LASzip 1.x, not chunked)", "pointwise chunked", "layered chunked"};
    throw unsupported(where, "laszip VLR: compressor " + std::to_string(compressor) +
                                 (compressor < 4 ? std::string(" (") + names[compressor] + ")" : std::string()) +
                                 " is not supported for point format " + std::to_string(point_format) + "; expected " +
                                 std::to_string(wanted) + " (" + names[wanted] + ")");
  }
  if (chunk_size == 0) throw bad_vlr(where, "chunk size 0");
  if (record_length < base) {
    throw bad_vlr(where, "record length " + std::to_string(record_length) + " is shorter than point format " +
                             std::to_string(point_format) + "'s " + std::to_string(base) + " bytes");
  }
  const LazVlr expected = for_format(point_format, record_length, chunk_size);
  // Same types and sizes in another version: name the version.
  if (items.size() == expected.items.size()) {
    for (std::size_t k = 0; k < items.size(); ++k) {
      const LazItem& got = items[k];
      const LazItem& want = expected.items[k];
      if (got.type == want.type && got.size == want.size && got.version != want.version) {
        throw unsupported(where, "laszip VLR: item " + std::to_string(k + 1) + " is " + laz_item_name(got.type) +
                                     " version " + std::to_string(got.version) + ", which is not supported; geoanchor " +
                                     "decodes version " + std::to_string(want.version) +
                                     (got.version < want.version ? " (recompress with a LASzip of 2012 or later)" : ""));
      }
    }
  }
  if (items != expected.items) {
    std::size_t sum = 0;
    for (const auto& i : items) sum += i.size;
    throw bad_vlr(where, "items " + describe(items) + " (" + std::to_string(sum) + " bytes) do not describe point format " +
                             std::to_string(point_format) + " with " + std::to_string(record_length) +
                             "-byte records; expected " + describe(expected.items));
  }
}

struct LazChunkEncoder::Impl {
  explicit Impl(const laz::ChunkLayout& l) : encoder(l) {}
  laz::ChunkEncoder encoder;
};

LazChunkEncoder::LazChunkEncoder(const LazVlr& vlr) {
  const laz::ChunkLayout l = chunk_layout(vlr, items_size(vlr));
  impl_ = std::make_unique<Impl>(l);
  record_length_ = l.record_length;
}
LazChunkEncoder::~LazChunkEncoder() = default;
LazChunkEncoder::LazChunkEncoder(LazChunkEncoder&&) noexcept = default;
LazChunkEncoder& LazChunkEncoder::operator=(LazChunkEncoder&&) noexcept = default;

void LazChunkEncoder::encode(const std::uint8_t* records, std::size_t n, std::vector<std::uint8_t>& chunk) {
  chunk.clear();
  impl_->encoder.encode(records, n, chunk);
}

struct LazChunkDecoder::Impl {
  explicit Impl(const laz::ChunkLayout& l) : decoder(l) {}
  laz::ChunkDecoder decoder;
};

LazChunkDecoder::LazChunkDecoder(const LazVlr& vlr) {
  const laz::ChunkLayout l = chunk_layout(vlr, items_size(vlr));
  impl_ = std::make_unique<Impl>(l);
  record_length_ = l.record_length;
}
LazChunkDecoder::~LazChunkDecoder() = default;
LazChunkDecoder::LazChunkDecoder(LazChunkDecoder&&) noexcept = default;
LazChunkDecoder& LazChunkDecoder::operator=(LazChunkDecoder&&) noexcept = default;

std::size_t LazChunkDecoder::decode(const std::uint8_t* chunk, std::size_t size, std::size_t n, std::uint8_t* records) {
  try {
    return impl_->decoder.decode(chunk, size, n, records);
  } catch (const laz::StreamOverrun&) {
    throw Error(ErrorKind::input, "E_LAZ_CHUNK",
                "the chunk (" + std::to_string(size) + " bytes) ends before its " + std::to_string(n) +
                    " points do: truncated or corrupt");
  } catch (const laz::StreamCorrupt& e) {
    throw Error(ErrorKind::input, "E_LAZ_CHUNK", std::string("the chunk is corrupt: ") + e.what);
  } catch (const laz::ChunkCountMismatch& m) {
    throw Error(ErrorKind::input, "E_LAZ_CHUNK",
                "the chunk states " + std::to_string(m.stored) + " points, not the " + std::to_string(n) + " asked for");
  }
}

}  // namespace geoanchor::io
