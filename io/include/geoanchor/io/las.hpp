#pragma once
// LAS 1.2–1.4 point clouds (ASPRS LAS 1.4 R15), uncompressed, point data
// record formats 0–3 and 6–8, read and written in bounded chunks so that
// memory does not grow with the tile.
//
// The reader validates the whole file layout up front (header size for the
// version, VLRs inside the header block, point data against the file size,
// EVLR chain) and names the file and byte offset of anything inconsistent.
// The writer always writes LAS 1.4 (375-byte header): the same point format
// and record length, the records as given (only X, Y, Z change), the VLRs
// and EVLRs it is handed, and a header whose counts and bounds are patched
// when the points are finished.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace geoanchor::io {

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

class LasReader {
 public:
  // Opens and validates the file; reads all VLRs and EVLRs. Throws
  // geoanchor::Error (io when unreadable, input for a malformed file) naming
  // the file and the byte offset: truncated header, unsupported version,
  // compressed (LAZ) or unknown point format, a record length too short for
  // the format, a VLR running past the start of the point data, a point count
  // that disagrees with the file size, a broken EVLR chain.
  explicit LasReader(const std::filesystem::path& path);
  ~LasReader();
  LasReader(const LasReader&) = delete;
  LasReader& operator=(const LasReader&) = delete;

  const LasHeader& header() const { return header_; }
  const std::vector<LasVlr>& vlrs() const { return vlrs_; }    // VLRs then EVLRs, in file order
  const std::filesystem::path& path() const { return path_; }
  // The WKT of the LASF_Projection 2112 record (VLR or EVLR), without the
  // trailing NULs.
  std::optional<std::string> wkt() const;

  // Reads up to `max_points` whole records into `buffer` (resized to
  // n × record_length) and returns n; 0 after the last point. Throws
  // geoanchor::Error (io) on a read error or a file that shrank.
  std::size_t read_records(std::vector<std::uint8_t>& buffer, std::size_t max_points);
  // Back to the first point.
  void rewind();

 private:
  std::filesystem::path path_;
  int fd_ = -1;
  LasHeader header_;
  std::vector<LasVlr> vlrs_;
  std::uint64_t next_point_ = 0;
};

class LasWriter {
 public:
  // Writes a provisional LAS 1.4 header and the VLRs to `out` (a binary,
  // seekable stream). `header` gives the point format, record length,
  // scale, offset and the pass-through fields; counts, bounds, offsets and
  // the version are filled in here. `name` is used in messages.
  LasWriter(std::ostream& out, const LasHeader& header, std::vector<LasVlr> vlrs, std::vector<LasVlr> evlrs,
            std::string name);

  void write_records(const std::uint8_t* data, std::size_t n);
  // Back to the first point, to write them all again with a new offset.
  void restart(const std::array<double, 3>& offset);

  // Writes the EVLRs, then rewrites the header with the point count, the
  // per-return counts and the bounds (in the file's own coordinates: X, Y,
  // Z after scale and offset). Throws geoanchor::Error (io) when the stream
  // failed.
  void finish(const std::array<std::uint64_t, 15>& points_by_return, const std::array<double, 3>& min,
              const std::array<double, 3>& max);

  const LasHeader& header() const { return header_; }

 private:
  std::ostream& out_;
  LasHeader header_;
  std::vector<LasVlr> evlrs_;
  std::string name_;
  std::uint64_t written_ = 0;
};

// The header bytes of a LAS 1.4 file (375 bytes), little-endian.
std::vector<std::uint8_t> encode_las14_header(const LasHeader& h);

}  // namespace geoanchor::io
