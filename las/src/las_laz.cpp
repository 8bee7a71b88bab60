// LasReader and LasWriter on LAZ files: the chunk table, chunk by chunk
// decoding and encoding. las.cpp reads the header and VLRs of both kinds.
//
// Layout of a LAZ point data block (LASzip; see laz.hpp): at the offset to
// point data, the int64 offset of the chunk table; then the chunks, back to
// back; then the chunk table: uint32 version (0), uint32 number of chunks,
// and the chunks' byte counts (and point counts, for variable-size chunks)
// coded with the integer coder. The EVLRs, if any, follow the table.

#include <algorithm>
#include <stdexcept>

#include "geoanchor/base/error.hpp"
#include "geoanchor/las/las.hpp"
#include "las_internal.hpp"
#include "laz_chunk.hpp"
#include "laz_entropy.hpp"
#include "laz_layout.hpp"

namespace geoanchor::io {
namespace {

using las_internal::get;
using las_internal::read_at;

// The chunk table's own header: version and number of chunks.
constexpr std::uint64_t kTableHeaderBytes = 8;
// An upper bound on one coded table entry (two 32-bit values: interval
// symbols of at most ~16 bits each, at most 24 raw and 15 adaptive bits of
// offset), to read no more of the file than a table can hold.
constexpr std::uint64_t kTableEntryMaxBytes = 24;
constexpr std::uint64_t kTableSlackBytes = 64;
// When the chunk table is missing, a chunk is looked for within this many
// bytes: twice its records (a coded chunk is at most a little larger) and some.
constexpr std::uint64_t kScanSlackBytes = 1 << 16;

Error table_error(const std::filesystem::path& p, std::uint64_t offset, const std::string& what) {
  return Error(ErrorKind::input, "E_LAZ_CHUNK_TABLE", p.string() + ": byte " + std::to_string(offset) + ": " + what);
}

std::string plural(std::uint64_t n, const char* what) { return std::to_string(n) + " " + what + (n == 1 ? "" : "s"); }

}  // namespace

void LasReader::open_laz(std::uint64_t file_size, const LasVlr& vlr) {
  const std::string where = path_.string() + ": byte " + std::to_string(vlr.file_offset);
  laz_ = LazVlr::parse(vlr.data, where);
  laz_->check(header_.point_format, header_.record_length, where);
  const LasHeader& h = header_;
  const std::uint64_t data_end = h.evlr_count > 0 ? h.evlr_start : file_size;
  const std::uint64_t chunks_start = std::uint64_t{h.offset_to_points} + 8;
  if (h.point_count == 0 && data_end < chunks_start) return;  // no points and not even the table offset
  if (chunks_start > data_end) {
    throw table_error(path_, h.offset_to_points, "the point data ends at byte " + std::to_string(data_end) +
                                                     ", before the 8-byte offset of the chunk table");
  }
  std::uint8_t b[8];
  if (!read_at(fd_, h.offset_to_points, b, 8)) throw las_internal::malformed(path_, h.offset_to_points, "cannot read");
  auto table_at = get<std::int64_t>(b);
  std::uint64_t points_end = data_end;  // where the chunks end when there is no table
  if (table_at == -1) {
    // Written to a stream that could not seek back: the offset ends the file.
    if (file_size < chunks_start + 8 || !read_at(fd_, file_size - 8, b, 8)) {
      throw table_error(path_, h.offset_to_points, "the chunk table offset is -1 (at the end of the file), but the file is too short");
    }
    table_at = get<std::int64_t>(b);
    points_end = std::min(data_end, file_size - 8);
  }
  if (table_at == static_cast<std::int64_t>(h.offset_to_points)) {
    // The writer stopped before the table: LASzip walks fixed-size chunks.
    if (laz_->variable_chunks()) {
      throw table_error(path_, h.offset_to_points,
                        "no chunk table (the writer stopped before writing it), and variable-size chunks cannot be "
                        "found without one");
    }
    scan_laz_chunks(points_end);
    return;
  }
  if (table_at < static_cast<std::int64_t>(chunks_start) ||
      static_cast<std::uint64_t>(table_at) + kTableHeaderBytes > data_end) {
    throw table_error(path_, h.offset_to_points,
                      "the chunk table offset " + std::to_string(table_at) + " is outside the point data [" +
                          std::to_string(chunks_start) + ", " + std::to_string(data_end) + ")" +
                          (static_cast<std::uint64_t>(table_at) >= file_size ? " (past the end of the file)" : ""));
  }
  const auto table = static_cast<std::uint64_t>(table_at);
  if (!read_at(fd_, table, b, 8)) throw las_internal::malformed(path_, table, "cannot read the chunk table");
  const auto version = get<std::uint32_t>(b);
  const auto count = get<std::uint32_t>(b + 4);
  if (version != 0) {
    throw Error(ErrorKind::input, "E_LAZ_UNSUPPORTED",
                path_.string() + ": byte " + std::to_string(table) + ": chunk table version " + std::to_string(version) +
                    " is not supported; 0 is the only one");
  }
  // Each chunk takes at least one byte before the table.
  if (count > table - chunks_start) {
    throw table_error(path_, table + 4, "the chunk table lists " + plural(count, "chunk") + ", more than the " +
                                            std::to_string(table - chunks_start) + " bytes of chunks can hold");
  }
  if (!laz_->variable_chunks()) {
    const std::uint64_t expected = (h.point_count + laz_->chunk_size - 1) / laz_->chunk_size;
    if (count != expected) {
      throw table_error(path_, table + 4,
                        "the chunk table lists " + plural(count, "chunk") + ", but " + plural(h.point_count, "point") +
                            " in chunks of " + std::to_string(laz_->chunk_size) + " make " + std::to_string(expected));
    }
  }
  std::vector<laz::ChunkEntry> entries;
  if (count > 0) {
    const std::uint64_t available = data_end - table - kTableHeaderBytes;
    const std::uint64_t take = std::min(available, kTableEntryMaxBytes * count + kTableSlackBytes);
    std::vector<std::uint8_t> coded(static_cast<std::size_t>(take));
    if (take && !read_at(fd_, table + kTableHeaderBytes, coded.data(), coded.size())) {
      throw las_internal::malformed(path_, table, "cannot read the chunk table");
    }
    try {
      entries = laz::decode_chunk_table(coded.data(), coded.size(), count, laz_->variable_chunks());
    } catch (const laz::StreamOverrun&) {
      throw table_error(path_, table, "the chunk table of " + plural(count, "chunk") + " is cut short (" +
                                          std::to_string(available) + " bytes before " +
                                          (h.evlr_count > 0 ? "the EVLRs)" : "the end of the file)"));
    }
  }
  std::uint64_t offset = chunks_start, first = 0;
  chunks_.reserve(count);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const auto& e = entries[i];
    ChunkSpan c;
    c.offset = offset;
    c.bytes = e.bytes;
    c.first_point = first;
    c.points = laz_->variable_chunks() ? e.points
                                       : static_cast<std::uint32_t>(std::min<std::uint64_t>(laz_->chunk_size, h.point_count - first));
    const std::string which = "chunk " + std::to_string(i) + " of " + std::to_string(count);
    if (c.bytes == 0) throw table_error(path_, offset, which + " has 0 bytes in the chunk table");
    if (c.points == 0) throw table_error(path_, offset, which + " has 0 points in the chunk table");
    check_chunk_points(c.points, offset, which);
    if (offset + c.bytes > table) {
      throw table_error(path_, offset, which + " (" + std::to_string(c.bytes) + " bytes) runs past the chunk table at byte " +
                                           std::to_string(table) + ": the chunk sizes do not add up to the point data");
    }
    if (laz_->variable_chunks() && c.points > h.point_count - first) {
      throw table_error(path_, offset, which + " holds " + plural(c.points, "point") + ", past the header's " +
                                           plural(h.point_count, "point") + " (the chunks before it hold " +
                                           std::to_string(first) + ")");
    }
    offset += c.bytes;
    first += c.points;
    chunks_.push_back(c);
  }
  if (offset != table) {
    throw table_error(path_, chunks_start, "the chunk sizes add up to " + std::to_string(offset - chunks_start) +
                                               " bytes, but the chunk table starts " + std::to_string(table - chunks_start) +
                                               " bytes after the first chunk");
  }
  if (first != h.point_count) {
    throw table_error(path_, table, "the chunk table counts " + plural(first, "point") + ", the header " +
                                        std::to_string(h.point_count));
  }
}

void LasReader::check_chunk_points(std::uint64_t points, std::uint64_t offset, const std::string& which) const {
  if (points <= kLazMaxChunkPoints) return;
  throw Error(ErrorKind::input, "E_LAZ_UNSUPPORTED",
              path_.string() + ": byte " + std::to_string(offset) + ": " + which + " holds " + plural(points, "point") +
                  "; chunks of more than " + std::to_string(kLazMaxChunkPoints) +
                  " points are not supported (a chunk is decoded whole, in memory)");
}

namespace {
// A chunk that holds more than the header's count gives it (issue 40
// point 8): refused, since the rest would be dropped.
// `holds_more`: the chunk holds more than the count gives it (the rest
// would be dropped); else fewer (the count promises points the file lacks).
Error point_count_mismatch(const std::filesystem::path& path, std::uint64_t offset, std::size_t chunk, std::size_t chunks,
                           std::uint64_t expected, std::uint64_t header_count, const std::string& what, bool holds_more) {
  return Error(ErrorKind::input, "E_LAZ_POINT_COUNT",
               path.string() + ": byte " + std::to_string(offset) + ": chunk " + std::to_string(chunk) + " of " +
                   std::to_string(chunks) + " should hold " + plural(expected, "point") + " by the header's count (" +
                   plural(header_count, "point") + ") but " + what +
                   (holds_more ? ": the header counts fewer points than the chunks hold, and the rest would be dropped"
                               : ": the header counts more points than the chunks hold"));
}
}  // namespace

void LasReader::scan_laz_chunks(std::uint64_t data_end) {
  const LasHeader& h = header_;
  check_chunk_points(std::min<std::uint64_t>(laz_->chunk_size, h.point_count), std::uint64_t{h.offset_to_points} + 8,
                     "chunk 0 (no chunk table)");
  laz::ChunkDecoder decoder(chunk_layout(*laz_, h.record_length));
  const std::uint64_t count = (h.point_count + laz_->chunk_size - 1) / laz_->chunk_size;
  std::uint64_t offset = std::uint64_t{h.offset_to_points} + 8, first = 0;
  std::vector<std::uint8_t> coded, records;
  for (std::uint64_t i = 0; i < count; ++i) {
    const auto n = static_cast<std::uint32_t>(std::min<std::uint64_t>(laz_->chunk_size, h.point_count - first));
    const std::uint64_t window = std::min(data_end - offset, 2 * std::uint64_t{n} * h.record_length + kScanSlackBytes);
    coded.resize(static_cast<std::size_t>(window));
    records.resize(std::size_t{n} * h.record_length);
    if (window && !read_at(fd_, offset, coded.data(), coded.size())) throw las_internal::malformed(path_, offset, "cannot read");
    const std::string which = "chunk " + std::to_string(i) + " of " + std::to_string(count) + " (no chunk table; " +
                              plural(n, "point") + ")";
    std::size_t used = 0;
    try {
      used = decoder.decode(coded.data(), coded.size(), n, records.data());
    } catch (const laz::StreamOverrun&) {
      throw Error(ErrorKind::input, "E_LAZ_CHUNK",
                  path_.string() + ": byte " + std::to_string(offset) + ": " + which +
                      " ends before its points do: the file is truncated");
    } catch (const laz::StreamCorrupt& e) {
      throw Error(ErrorKind::input, "E_LAZ_CHUNK",
                  path_.string() + ": byte " + std::to_string(offset) + ": " + which + " is corrupt: " + e.what);
    } catch (const laz::ChunkCountMismatch& m) {
      throw point_count_mismatch(path_, offset, static_cast<std::size_t>(i), static_cast<std::size_t>(count), n, h.point_count,
                                 "states " + plural(m.stored, "point"), m.stored > n);
    }
    chunks_.push_back({offset, used, first, n});
    offset += used;
    first += n;
  }
  // Each chunk decodes to its last byte, so the header's points end where
  // the point data does, or where a chunk table the offset does not point
  // at starts (version 0, this many chunks). Another chunk there holds
  // points the header does not count (issue 40 point 8): refused, since
  // they would be dropped; other bytes are not understood: refused too.
  if (offset == data_end) return;
  std::uint8_t table_head[8];
  if (data_end - offset >= kTableHeaderBytes && read_at(fd_, offset, table_head, 8) && get<std::uint32_t>(table_head) == 0 &&
      get<std::uint32_t>(table_head + 4) == count) {
    return;
  }
  const auto n = static_cast<std::uint32_t>(laz_->chunk_size);
  const std::uint64_t window = std::min(data_end - offset, 2 * std::uint64_t{n} * h.record_length + kScanSlackBytes);
  coded.resize(static_cast<std::size_t>(window));
  records.resize(std::size_t{n} * h.record_length);
  bool another_chunk = false;
  if (read_at(fd_, offset, coded.data(), coded.size())) {
    try {
      (void)decoder.decode(coded.data(), coded.size(), n, records.data());
      another_chunk = true;
    } catch (const laz::ChunkCountMismatch&) {
      another_chunk = true;  // a chunk, of fewer points
    } catch (const laz::StreamOverrun&) {
    } catch (const laz::StreamCorrupt&) {
    }
  }
  if (another_chunk) {
    throw Error(ErrorKind::input, "E_LAZ_POINT_COUNT",
                path_.string() + ": byte " + std::to_string(offset) + ": the " + plural(h.point_count, "point") +
                    " the header counts end here, but another chunk follows (no chunk table): the header counts fewer "
                    "points than the chunks hold, and the rest would be dropped");
  }
  throw Error(ErrorKind::input, "E_LAZ_CHUNK",
              path_.string() + ": byte " + std::to_string(offset) + ": " + std::to_string(data_end - offset) +
                  " bytes after the last chunk the header's count implies are neither a chunk nor a chunk table");
}

std::size_t LasReader::chunk_count() const {
  if (laz_) return chunks_.size();
  return static_cast<std::size_t>((header_.point_count + kLasChunkPoints - 1) / kLasChunkPoints);
}

std::uint64_t LasReader::chunk_points(std::size_t i) const {
  if (laz_) return chunks_.at(i).points;
  if (i >= chunk_count()) throw std::out_of_range("LasReader::chunk_points");
  return std::min<std::uint64_t>(kLasChunkPoints, header_.point_count - std::uint64_t{i} * kLasChunkPoints);
}

std::uint64_t LasReader::chunk_first_point(std::size_t i) const {
  if (laz_) return chunks_.at(i).first_point;
  if (i >= chunk_count()) throw std::out_of_range("LasReader::chunk_first_point");
  return std::uint64_t{i} * kLasChunkPoints;
}

std::uint64_t LasReader::chunk_offset(std::size_t i) const {
  if (laz_) return chunks_.at(i).offset;
  return header_.offset_to_points + chunk_first_point(i) * header_.record_length;
}

void LasReader::decode_chunk(std::size_t i, std::vector<std::uint8_t>& records) const {
  const std::size_t len = header_.record_length;
  if (!laz_) {
    const std::uint64_t offset = chunk_offset(i);
    records.resize(static_cast<std::size_t>(chunk_points(i)) * len);
    if (!records.empty() && !read_at(fd_, offset, records.data(), records.size())) {
      throw Error(ErrorKind::io, "E_READ", path_.string() + ": byte " + std::to_string(offset) +
                                               ": cannot read point records (the file shrank or a read failed)");
    }
    return;
  }
  const ChunkSpan& c = chunks_.at(i);
  std::vector<std::uint8_t> coded(static_cast<std::size_t>(c.bytes));
  if (!read_at(fd_, c.offset, coded.data(), coded.size())) {
    throw Error(ErrorKind::io, "E_READ", path_.string() + ": byte " + std::to_string(c.offset) + ": cannot read chunk " +
                                             std::to_string(i) + " (the file shrank or a read failed)");
  }
  records.resize(std::size_t{c.points} * len);
  const std::string which = "chunk " + std::to_string(i) + " of " + std::to_string(chunks_.size()) + " (" +
                            plural(c.points, "point") + ", " + std::to_string(c.bytes) + " bytes)";
  // A decoder from the pool (returned whatever happens: every chunk starts afresh).
  struct Borrowed {
    const LasReader& reader;
    std::unique_ptr<laz::ChunkDecoder> decoder;
    ~Borrowed() {
      const std::lock_guard<std::mutex> lock(reader.decoders_mutex_);
      reader.decoders_.push_back(std::move(decoder));
    }
  } borrowed{*this, nullptr};
  {
    const std::lock_guard<std::mutex> lock(decoders_mutex_);
    if (!decoders_.empty()) {
      borrowed.decoder = std::move(decoders_.back());
      decoders_.pop_back();
    }
  }
  if (!borrowed.decoder) borrowed.decoder = std::make_unique<laz::ChunkDecoder>(chunk_layout(*laz_, header_.record_length));
  std::size_t used = 0;
  try {
    used = borrowed.decoder->decode(coded.data(), coded.size(), c.points, records.data());
  } catch (const laz::ChunkCountMismatch& m) {
    const bool more = m.stored > c.points;
    throw point_count_mismatch(path_, c.offset, i, chunks_.size(), c.points, header_.point_count,
                               "holds " + plural(m.stored, "point") +
                                   (more ? " (the chunks hold " + plural(header_.point_count - c.points + m.stored, "point") + ")"
                                         : std::string()),
                               more);
  } catch (const laz::StreamOverrun&) {
    throw Error(ErrorKind::input, "E_LAZ_CHUNK",
                path_.string() + ": byte " + std::to_string(c.offset) + ": " + which +
                    " ends before its points do: truncated or corrupt");
  } catch (const laz::StreamCorrupt& e) {
    throw Error(ErrorKind::input, "E_LAZ_CHUNK",
                path_.string() + ": byte " + std::to_string(c.offset) + ": " + which + " is corrupt: " + e.what);
  }
  // A chunk decodes to its last byte (LASzip's and geoanchor's both):
  // bytes left over are points the header does not count.
  if (used != c.bytes) {
    // How many points it does hold: the count whose decoding ends at its
    // last byte (more overrun it), found by bisection; only on this error.
    const auto decodes_to = [&](std::uint64_t n) -> std::optional<std::size_t> {
      records.resize(static_cast<std::size_t>(n) * header_.record_length);
      try {
        return borrowed.decoder->decode(coded.data(), coded.size(), static_cast<std::uint32_t>(n), records.data());
      } catch (const laz::StreamOverrun&) {
      } catch (const laz::StreamCorrupt&) {
      } catch (const laz::ChunkCountMismatch&) {
      }
      return std::nullopt;
    };
    // decodes_to(lo) ends early; find the least n that does not. A chunk of
    // fixed-size chunks holds at most chunk_size points.
    std::uint64_t lo = c.points;
    std::uint64_t hi = laz_->variable_chunks() ? kLazMaxChunkPoints : std::min<std::uint64_t>(laz_->chunk_size, kLazMaxChunkPoints);
    if (hi <= lo) hi = lo + 1;
    while (hi - lo > 1) {
      const std::uint64_t mid = lo + (hi - lo) / 2;
      const auto u = decodes_to(mid);
      (u && *u < c.bytes ? lo : hi) = mid;
    }
    const auto at_hi = decodes_to(hi);
    std::string what = "has " + std::to_string(c.bytes - used) + " bytes left after them";
    if (at_hi && *at_hi == c.bytes) {
      what = "holds " + plural(hi, "point") + " (the chunks hold " +
             plural(header_.point_count - c.points + hi, "point") + ")";
    }
    throw point_count_mismatch(path_, c.offset, i, chunks_.size(), c.points, header_.point_count, what, true);
  }
}

std::size_t LasReader::read_laz_records(std::vector<std::uint8_t>& buffer, std::size_t max_points) {
  const std::size_t len = header_.record_length;
  const std::uint64_t left = header_.point_count - next_point_;
  const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(left, max_points));
  buffer.resize(n * len);
  std::size_t done = 0;
  while (done < n) {
    if (chunk_used_ * len == chunk_records_.size()) {
      decode_chunk(chunk_next_++, chunk_records_);
      chunk_used_ = 0;
    }
    const std::size_t take = std::min(n - done, chunk_records_.size() / len - chunk_used_);
    std::copy_n(chunk_records_.begin() + static_cast<std::ptrdiff_t>(chunk_used_ * len), take * len,
                buffer.begin() + static_cast<std::ptrdiff_t>(done * len));
    chunk_used_ += take;
    done += take;
  }
  next_point_ += n;
  return n;
}

void LasWriter::flush_gathered() {
  const std::size_t points = gathered_.size() / header_.record_length;
  if (points == 0) return;
  encoder_->encode(gathered_.data(), points, chunk_);
  append_chunk(chunk_.data(), chunk_.size(), points);
  gathered_.clear();
}

void LasWriter::write_chunk(const std::vector<std::uint8_t>& chunk, std::size_t points) {
  if (!laz_) throw std::logic_error(name_ + ": write_chunk on an uncompressed LAS output");
  if (!gathered_.empty()) {
    throw std::logic_error(name_ + ": write_chunk while records from write_records are still gathering into a chunk");
  }
  append_chunk(chunk.data(), chunk.size(), points);
}

void LasWriter::append_chunk(const std::uint8_t* bytes, std::size_t size, std::size_t points) {
  if (points == 0) return;
  if (short_chunk_) {
    throw std::logic_error(name_ + ": a chunk after one of fewer than " + std::to_string(laz_->chunk_size) +
                           " points (only the last chunk may be short)");
  }
  if (points > laz_->chunk_size) {
    throw std::logic_error(name_ + ": a chunk of " + std::to_string(points) + " points; chunks hold " +
                           std::to_string(laz_->chunk_size));
  }
  if (size > UINT32_MAX) {
    throw Error(ErrorKind::input, "E_LAZ_CHUNK",
                name_ + ": a compressed chunk of " + std::to_string(size) + " bytes; the chunk table holds at most 4 GiB - 1");
  }
  if (points < laz_->chunk_size) short_chunk_ = true;
  out_.write(reinterpret_cast<const char*>(bytes), static_cast<std::streamsize>(size));
  table_.push_back({static_cast<std::uint32_t>(points), static_cast<std::uint32_t>(size)});
  written_ += points;
}

std::uint64_t LasWriter::finish_laz_chunks() {
  flush_gathered();
  const auto table_at = static_cast<std::uint64_t>(static_cast<std::streamoff>(out_.tellp()));
  std::vector<laz::ChunkEntry> entries;
  entries.reserve(table_.size());
  for (const auto& t : table_) entries.push_back({t[0], t[1]});
  const std::uint32_t head[2] = {0, static_cast<std::uint32_t>(entries.size())};
  out_.write(reinterpret_cast<const char*>(head), sizeof head);
  const auto coded = laz::encode_chunk_table(entries, false);
  out_.write(reinterpret_cast<const char*>(coded.data()), static_cast<std::streamsize>(coded.size()));
  const std::uint64_t end = table_at + sizeof head + coded.size();
  out_.seekp(static_cast<std::streamoff>(header_.offset_to_points));
  out_.write(reinterpret_cast<const char*>(&table_at), sizeof table_at);
  out_.seekp(static_cast<std::streamoff>(end));
  return end;
}

}  // namespace geoanchor::io
