// The chunk encoder and decoder (laz_chunk.hpp), each on the chunk kind its
// layout names (laz_chunk_kinds.hpp), and the chunk table.

#include "laz_chunk.hpp"

#include "laz_chunk_kinds.hpp"
#include "laz_entropy.hpp"

namespace geoanchor::io::laz {
namespace {

std::unique_ptr<ChunkCoder> make_coder(const ChunkLayout& l, bool decoding) {
  return l.layered ? make_layered_coder(l, decoding) : make_pointwise_coder(l, decoding);
}

}  // namespace

struct ChunkEncoder::Impl {
  explicit Impl(const ChunkLayout& l) : coder(make_coder(l, false)) {}
  std::unique_ptr<ChunkCoder> coder;
};

ChunkEncoder::ChunkEncoder(const ChunkLayout& layout) : impl_(std::make_unique<Impl>(layout)) {}
ChunkEncoder::~ChunkEncoder() = default;
ChunkEncoder::ChunkEncoder(ChunkEncoder&&) noexcept = default;
ChunkEncoder& ChunkEncoder::operator=(ChunkEncoder&&) noexcept = default;

void ChunkEncoder::encode(const std::uint8_t* records, std::size_t n, std::vector<std::uint8_t>& out) {
  if (n == 0) return;
  impl_->coder->encode(records, n, out);
}

struct ChunkDecoder::Impl {
  explicit Impl(const ChunkLayout& l) : coder(make_coder(l, true)) {}
  std::unique_ptr<ChunkCoder> coder;
};

ChunkDecoder::ChunkDecoder(const ChunkLayout& layout) : impl_(std::make_unique<Impl>(layout)) {}
ChunkDecoder::~ChunkDecoder() = default;
ChunkDecoder::ChunkDecoder(ChunkDecoder&&) noexcept = default;
ChunkDecoder& ChunkDecoder::operator=(ChunkDecoder&&) noexcept = default;

std::size_t ChunkDecoder::decode(const std::uint8_t* data, std::size_t size, std::size_t n, std::uint8_t* out) {
  if (n == 0) return 0;
  return impl_->coder->decode(data, size, n, out);
}

std::vector<std::uint8_t> encode_chunk_table(const std::vector<ChunkEntry>& chunks, bool with_points) {
  std::vector<std::uint8_t> out;
  if (chunks.empty()) return out;
  RangeEncoder e(out);
  IntegerCoder ic(32, 2, false);
  ChunkEntry prev;
  for (const auto& c : chunks) {
    if (with_points) ic.encode(e, static_cast<std::int32_t>(prev.points), static_cast<std::int32_t>(c.points), 0);
    ic.encode(e, static_cast<std::int32_t>(prev.bytes), static_cast<std::int32_t>(c.bytes), 1);
    prev = c;
  }
  e.finish();
  return out;
}

std::vector<ChunkEntry> decode_chunk_table(const std::uint8_t* data, std::size_t size, std::size_t count,
                                           bool with_points) {
  std::vector<ChunkEntry> chunks(count);
  if (count == 0) return chunks;
  RangeDecoder d;
  d.start(data, data + size);
  IntegerCoder ic(32, 2, true);
  ChunkEntry prev;
  for (auto& c : chunks) {
    if (with_points) c.points = static_cast<std::uint32_t>(ic.decode(d, static_cast<std::int32_t>(prev.points), 0));
    c.bytes = static_cast<std::uint32_t>(ic.decode(d, static_cast<std::int32_t>(prev.bytes), 1));
    prev = c;
  }
  return chunks;
}

}  // namespace geoanchor::io::laz