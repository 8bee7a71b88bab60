#pragma once
// The two chunk kinds behind ChunkEncoder and ChunkDecoder (laz_chunk.hpp):
// pointwise (laz_pointwise.cpp) and layered (laz_layered.cpp), each made for
// one direction.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "laz_chunk.hpp"

namespace geoanchor::io::laz {

// One chunk kind's coder: encode() on one made for encoding, decode() on one
// made for decoding (as ChunkEncoder::encode and ChunkDecoder::decode, n >= 1).
class ChunkCoder {
 public:
  virtual ~ChunkCoder() = default;
  virtual void encode(const std::uint8_t* records, std::size_t n, std::vector<std::uint8_t>& out) = 0;
  virtual std::size_t decode(const std::uint8_t* data, std::size_t size, std::size_t n, std::uint8_t* out) = 0;
};

// Compressor 2: POINT10 v2, GPSTIME11 v2, RGB12 v2, BYTE v2.
std::unique_ptr<ChunkCoder> make_pointwise_coder(const ChunkLayout& layout, bool decoding);
// Compressor 3: POINT14 v3, RGB14 / RGBNIR14 v3, BYTE14 v3.
std::unique_ptr<ChunkCoder> make_layered_coder(const ChunkLayout& layout, bool decoding);

}  // namespace geoanchor::io::laz
