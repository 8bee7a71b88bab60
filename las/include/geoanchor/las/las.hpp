#pragma once
// LAS 1.2–1.4 point clouds (ASPRS LAS 1.4 R15), uncompressed or LAZ
// (LASzip-compressed, laz.hpp), point data record formats 0–3 and 6–8, read
// and written in bounded chunks so that memory does not grow with the tile.
//
// The reader validates the whole file layout up front (header size for the
// version, VLRs inside the header block, point data against the file size,
// EVLR chain; for LAZ the laszip VLR against the header and the chunk table
// against the file) and names the file and byte offset of anything
// inconsistent. A LAZ file reads as the uncompressed file would: the same
// header (point format without the compression bits), VLRs and records.
// The writer always writes LAS 1.4 (375-byte header): the same point format
// and record length, the records as given (only X, Y, Z change), the VLRs
// and EVLRs it is handed, and a header whose counts and bounds are patched
// when the points are finished; on request the points are LAZ.
//
// Chunks: both sides work in chunks that can be decoded or encoded on
// threads of their own (LasReader::decode_chunk, LazChunkEncoder and
// LasWriter::write_chunk), so that one tile's chunks run on every thread
// with a few chunks of memory per thread.

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "geoanchor/las/laz.hpp"

namespace geoanchor::io {

namespace laz {
class ChunkDecoder;
}

struct LasVlr {
  std::string user_id;  // up to 16 characters ("LASF_Projection", "LASF_Spec")
  std::uint16_t record_id = 0;
  std::string description;  // up to 32 characters
  std::vector<std::uint8_t> data;
  bool extended = false;       // an EVLR (stored after the points)
  std::uint64_t file_offset = 0;  // where its header starts in the source file (messages)
};

// Record id of the OGC WKT coordinate system VLR (user id LASF_Projection).
inline constexpr std::uint16_t kLasWktRecordId = 2112;
// GeoTIFF keys, double and ASCII params (LASF_Projection): the legacy CRS.
bool is_geotiff_crs_vlr(const LasVlr& v);
// The WKT CRS VLR (LASF_Projection 2112), and the WKT math-transform VLR (2111).
bool is_wkt_crs_vlr(const LasVlr& v);

struct LasHeader {
  std::uint8_t version_major = 1;
  std::uint8_t version_minor = 4;
  std::uint16_t file_source_id = 0;
  std::uint16_t global_encoding = 0;
  std::array<std::uint8_t, 16> project_guid{};
  std::array<char, 32> system_identifier{};
  std::array<char, 32> generating_software{};
  std::uint16_t creation_day = 0;
  std::uint16_t creation_year = 0;
  std::uint16_t header_size = 375;
  std::uint32_t offset_to_points = 375;
  std::uint32_t vlr_count = 0;
  std::uint8_t point_format = 6;
  std::uint16_t record_length = 30;
  std::uint64_t point_count = 0;
  std::array<std::uint64_t, 15> points_by_return{};
  std::array<double, 3> scale{0.001, 0.001, 0.001};
  std::array<double, 3> offset{};
  std::array<double, 3> min{};
  std::array<double, 3> max{};
  std::uint64_t evlr_start = 0;
  std::uint32_t evlr_count = 0;

  static constexpr std::uint16_t kWktBit = 1u << 4;
  bool wkt_bit() const { return (global_encoding & kWktBit) != 0; }
};

// The smallest record length of a point data record format, or 0 for a
// format this reader does not support.
std::size_t las_min_record_length(std::uint8_t point_format);

// One attribute of the LAS 1.4 extra-bytes VLR (user id "LASF_Spec",
// record id 4; R15 Table 24: 192 bytes per attribute, in record order).
struct LasExtraBytes {
  std::string name;
  std::uint8_t data_type = 0;  // 0 undocumented (options = size), 1 uint8, 2 int8, 3 uint16, … 10 double, 11–30 arrays
  std::uint8_t options = 0;    // bit 0 no_data, 1 min, 2 max, 3 scale, 4 offset
  std::size_t offset = 0;      // byte offset of the attribute in a point record
  std::size_t size = 0;        // its bytes
};
inline constexpr std::uint16_t kLasExtraBytesRecordId = 4;
// The extra-bytes attribute that carries each point's GNSS solution type
// (uint8, the codes of geodesy::gnss_solution_from_code: 1 fixed … 7
// dead_reckoned).
inline constexpr std::string_view kGnssSolutionAttribute = "gnss_solution";

// The attributes of `vlrs`' extra-bytes VLR for records of `point_format`
// and `record_length` (none without that VLR). Throws geoanchor::Error
// (input, E_LAS_EXTRA_BYTES) naming `file` and the VLR's byte offset: a
// length that is no multiple of 192, an unknown data type, attributes
// longer than the record's extra bytes, a name given twice.
std::vector<LasExtraBytes> las_extra_bytes(const std::vector<LasVlr>& vlrs, std::uint8_t point_format,
                                           std::uint16_t record_length, const std::string& file);

// The records per chunk LasReader reports for an uncompressed file (a LAZ
// file has the chunks it was written with).
inline constexpr std::uint32_t kLasChunkPoints = 50000;
// The most points a LAZ chunk may hold for LasReader: a chunk is decoded
// whole, so this bounds the memory a (malformed) chunk table can ask for
// (LASzip's default is 50 000; COPC nodes hold some 10^5).
inline constexpr std::uint32_t kLazMaxChunkPoints = 1u << 22;

class LasReader {
 public:
  // Opens and validates the file; reads all VLRs and EVLRs. Throws
  // geoanchor::Error (io when unreadable, input for a malformed file) naming
  // the file and the byte offset: truncated header, unsupported version,
  // unknown or waveform point format, a record length too short for the
  // format, a VLR running past the start of the point data, a point count
  // that disagrees with the file size, a broken EVLR chain. For LAZ also:
  // E_LAZ_VLR (laszip VLR missing, malformed or contradicting the header),
  // E_LAZ_UNSUPPORTED (a compressor, coder, item or version not implemented,
  // named), E_LAZ_CHUNK_TABLE (a chunk table that disagrees with the file:
  // its offset outside the point data, chunk sizes that do not add up to
  // it, point counts that do not add up to the header's, a truncated table).
  // A LAZ file whose writer stopped before the chunk table (the table offset
  // still points at itself) is read by walking its chunks, as LASzip does,
  // when the chunks have a fixed size; with variable-size chunks it is an
  // error. A chunk of more than kLazMaxChunkPoints points is refused
  // (E_LAZ_UNSUPPORTED).
  explicit LasReader(const std::filesystem::path& path);
  ~LasReader();
  LasReader(const LasReader&) = delete;
  LasReader& operator=(const LasReader&) = delete;

  // The header as an uncompressed file would have it (point format 0–10,
  // the compression bits 0x80/0x40 of a LAZ file cleared).
  const LasHeader& header() const { return header_; }
  // VLRs then EVLRs, in file order, without the laszip VLR (laz()): a
  // compression record is not carried into another file.
  const std::vector<LasVlr>& vlrs() const { return vlrs_; }
  const std::filesystem::path& path() const { return path_; }
  // The WKT of the LASF_Projection 2112 record (VLR or EVLR), without the
  // trailing NULs.
  std::optional<std::string> wkt() const;
  // A LAZ file, and its laszip VLR (nullptr for an uncompressed file).
  bool compressed() const { return laz_.has_value(); }
  const LazVlr* laz() const { return laz_ ? &*laz_ : nullptr; }

  // Reads up to `max_points` whole records into `buffer` (resized to
  // n × record_length) and returns n; 0 after the last point. LAZ records
  // come out as the uncompressed file would hold them. Throws
  // geoanchor::Error (io) on a read error or a file that shrank, (input,
  // E_LAZ_CHUNK) on a corrupt chunk as decode_chunk does.
  std::size_t read_records(std::vector<std::uint8_t>& buffer, std::size_t max_points);
  // Back to the first point.
  void rewind();

  // The point data in chunks, for reading on several threads: a LAZ file's
  // chunks as stored, an uncompressed file's records in runs of
  // kLasChunkPoints. Chunk i holds chunk_points(i) records starting at
  // record chunk_first_point(i); its bytes start at chunk_offset(i).
  std::size_t chunk_count() const;
  std::uint64_t chunk_points(std::size_t i) const;
  std::uint64_t chunk_first_point(std::size_t i) const;
  std::uint64_t chunk_offset(std::size_t i) const;
  // Reads (and for LAZ decompresses) chunk i into `records` (resized to
  // chunk_points(i) × record_length). Thread-safe: it reads with pread and
  // touches no shared state, so any number of threads may decode chunks at
  // once, each into its own buffer; memory per call is the chunk's records
  // and compressed bytes plus the decoder's models. Throws geoanchor::Error
  // (input, E_LAZ_CHUNK) naming the file, the chunk's byte offset and its
  // index when a chunk is truncated or corrupt (decoding never reads past
  // the chunk's end), (io, E_READ) when the file cannot be read.
  void decode_chunk(std::size_t i, std::vector<std::uint8_t>& records) const;

 private:
  // A LAZ chunk: where its bytes are and which records it holds.
  struct ChunkSpan {
    std::uint64_t offset = 0;
    std::uint64_t bytes = 0;
    std::uint64_t first_point = 0;
    std::uint32_t points = 0;
  };
  void open_laz(std::uint64_t file_size, const LasVlr& vlr);
  void scan_laz_chunks(std::uint64_t data_end);
  void check_chunk_points(std::uint64_t points, std::uint64_t offset, const std::string& which) const;
  std::size_t read_laz_records(std::vector<std::uint8_t>& buffer, std::size_t max_points);

  std::filesystem::path path_;
  int fd_ = -1;
  LasHeader header_;
  std::vector<LasVlr> vlrs_;
  std::uint64_t next_point_ = 0;
  std::optional<LazVlr> laz_;
  std::vector<ChunkSpan> chunks_;  // LAZ only
  // read_records on a LAZ file: the decoded chunk and how much of it is handed out.
  std::vector<std::uint8_t> chunk_records_;
  std::size_t chunk_next_ = 0;
  std::size_t chunk_used_ = 0;
  // Decoders for reuse by decode_chunk on any thread (a decoder's models
  // take some 0.5 MB per scanner channel; allocating them for every small
  // chunk of a COPC file cost more than decoding it).
  mutable std::mutex decoders_mutex_;
  mutable std::vector<std::unique_ptr<laz::ChunkDecoder>> decoders_;
};

// How LasWriter stores the points.
struct LasCompression {
  bool laz = false;  // LAZ (LASzip chunks, laz.hpp) instead of plain records
  std::uint32_t chunk_points = kLazDefaultChunkPoints;
};

class LasWriter {
 public:
  // Writes a provisional LAS 1.4 header and the VLRs to `out` (a binary,
  // seekable stream). `header` gives the point format, record length,
  // scale, offset and the pass-through fields; counts, bounds, offsets and
  // the version are filled in here. `name` is used in messages. A laszip VLR
  // among `vlrs` is dropped (it described another file's compression).
  // With `compression.laz` the file is LAZ: point format byte with bit 7
  // set, the writer's own laszip VLR after the others, chunks of
  // `compression.chunk_points` records, the chunk table after the last
  // chunk. Throws geoanchor::Error (input, E_LAZ_UNSUPPORTED) for a LAZ
  // output in a waveform format (4, 5, 9, 10).
  LasWriter(std::ostream& out, const LasHeader& header, std::vector<LasVlr> vlrs, std::vector<LasVlr> evlrs,
            std::string name, LasCompression compression = {});
  ~LasWriter();
  LasWriter(const LasWriter&) = delete;
  LasWriter& operator=(const LasWriter&) = delete;

  // LAZ: records are gathered into chunks and compressed on this thread.
  void write_records(const std::uint8_t* data, std::size_t n);
  // LAZ only: appends a chunk of `points` records compressed elsewhere
  // (LazChunkEncoder on laz(), any thread), as the next chunk. Every chunk
  // but the last holds chunk_points() records. Throws std::logic_error when
  // the output is not LAZ, records from write_records are still gathering,
  // or a short chunk was already written; geoanchor::Error (input, E_LAZ_CHUNK)
  // for a chunk of 4 GiB or more.
  void write_chunk(const std::vector<std::uint8_t>& chunk, std::size_t points);
  // Back to the first point, to write them all again with a new offset.
  // Uncompressed output only: a LAZ pass has another length, and a stream
  // cannot be shortened (std::logic_error); write a LAZ again to a new stream.
  void restart(const std::array<double, 3>& offset);

  // Writes the EVLRs, then rewrites the header with the point count, the
  // per-return counts and the bounds (in the file's own coordinates: X, Y,
  // Z after scale and offset). LAZ: first the last chunk and the chunk
  // table. Throws geoanchor::Error (io) when the stream failed.
  void finish(const std::array<std::uint64_t, 15>& points_by_return, const std::array<double, 3>& min,
              const std::array<double, 3>& max);

  const LasHeader& header() const { return header_; }
  bool compressed() const { return laz_.has_value(); }
  // The output's laszip VLR: what LazChunkEncoder needs (nullptr for LAS).
  const LazVlr* laz() const { return laz_ ? &*laz_ : nullptr; }
  std::uint32_t chunk_points() const { return laz_ ? laz_->chunk_size : 0; }

 private:
  void flush_gathered();
  void append_chunk(const std::uint8_t* bytes, std::size_t size, std::size_t points);
  // Writes the gathered records, the chunk table and its offset; returns where the table ends.
  std::uint64_t finish_laz_chunks();

  std::ostream& out_;
  LasHeader header_;
  std::vector<LasVlr> evlrs_;
  std::string name_;
  std::uint64_t written_ = 0;
  // LAZ output.
  std::optional<LazVlr> laz_;
  std::optional<LazChunkEncoder> encoder_;
  std::vector<std::uint8_t> gathered_;  // records waiting for a whole chunk
  std::vector<std::uint8_t> chunk_;
  std::vector<std::array<std::uint32_t, 2>> table_;  // per chunk: points, bytes
  bool short_chunk_ = false;
};

// The header bytes of a LAS 1.4 file (375 bytes), little-endian. The
// point format byte is written as given (a LAZ writer sets bit 7).
std::vector<std::uint8_t> encode_las14_header(const LasHeader& h);

}  // namespace geoanchor::io
