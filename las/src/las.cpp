#include "geoanchor/las/las.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "geoanchor/base/error.hpp"
#include "las_internal.hpp"
#include "laz_chunk.hpp"  // LasReader's decoders, destroyed here

namespace geoanchor::io {
namespace {

using las_internal::get;
using las_internal::kEvlrHeaderSize;
using las_internal::kHeaderSize12;
using las_internal::kHeaderSize13;
using las_internal::kHeaderSize14;
using las_internal::kVlrHeaderSize;
using las_internal::malformed;
using las_internal::put;
using las_internal::read_at;

std::string fixed_text(const std::uint8_t* p, std::size_t n) {
  std::size_t len = 0;
  while (len < n && p[len] != 0) ++len;
  return std::string(reinterpret_cast<const char*>(p), len);
}

void put_text(std::vector<std::uint8_t>& b, std::size_t at, const std::string& s, std::size_t n) {
  std::memset(b.data() + at, 0, n);
  std::memcpy(b.data() + at, s.data(), std::min(n, s.size()));
}

bool is_laz_vlr(const LasVlr& v) { return !v.extended && v.user_id == kLazVlrUserId && v.record_id == kLazVlrRecordId; }

}  // namespace

bool is_geotiff_crs_vlr(const LasVlr& v) {
  return v.user_id == "LASF_Projection" && (v.record_id == 34735 || v.record_id == 34736 || v.record_id == 34737);
}

bool is_wkt_crs_vlr(const LasVlr& v) {
  return v.user_id == "LASF_Projection" && (v.record_id == kLasWktRecordId || v.record_id == 2111);
}

std::vector<LasExtraBytes> las_extra_bytes(const std::vector<LasVlr>& vlrs, std::uint8_t point_format,
                                           std::uint16_t record_length, const std::string& file) {
  constexpr std::size_t kDescriptor = 192;  // R15 Table 24
  std::vector<LasExtraBytes> out;
  const LasVlr* vlr = nullptr;
  for (const auto& v : vlrs) {
    if (v.user_id == "LASF_Spec" && v.record_id == kLasExtraBytesRecordId) {
      if (vlr) {
        throw Error(ErrorKind::input, "E_LAS_EXTRA_BYTES",
                    file + ": byte " + std::to_string(v.file_offset) + ": a second extra-bytes VLR (LASF_Spec 4); the "
                    "first is at byte " + std::to_string(vlr->file_offset));
      }
      vlr = &v;
    }
  }
  if (!vlr) return out;
  const std::string at = file + ": byte " + std::to_string(vlr->file_offset) + ": extra-bytes VLR (LASF_Spec 4): ";
  if (vlr->data.size() % kDescriptor != 0) {
    throw Error(ErrorKind::input, "E_LAS_EXTRA_BYTES",
                at + std::to_string(vlr->data.size()) + " bytes, not a multiple of the 192-byte attribute descriptor");
  }
  // Bytes of one value of each data type 1..10 (R15 Table 25).
  static constexpr std::size_t kSizes[] = {0, 1, 1, 2, 2, 4, 4, 8, 8, 4, 8};
  std::size_t offset = las_min_record_length(point_format);
  for (std::size_t k = 0; k < vlr->data.size() / kDescriptor; ++k) {
    const std::uint8_t* d = vlr->data.data() + k * kDescriptor;
    LasExtraBytes a;
    a.data_type = d[2];
    a.options = d[3];
    const char* name = reinterpret_cast<const char*>(d + 4);
    a.name.assign(name, strnlen(name, 32));
    if (a.data_type == 0) {
      a.size = a.options;  // undocumented bytes: options holds their count
    } else if (a.data_type <= 10) {
      a.size = kSizes[a.data_type];
    } else if (a.data_type <= 20) {
      a.size = 2 * kSizes[a.data_type - 10];  // deprecated two-element arrays
    } else if (a.data_type <= 30) {
      a.size = 3 * kSizes[a.data_type - 20];  // deprecated three-element arrays
    } else {
      throw Error(ErrorKind::input, "E_LAS_EXTRA_BYTES",
                  at + "attribute " + std::to_string(k + 1) + " '" + a.name + "': data type " + std::to_string(a.data_type) +
                      " unknown; expected 0 to 30");
    }
    for (const auto& b : out) {
      if (!a.name.empty() && b.name == a.name) {
        throw Error(ErrorKind::input, "E_LAS_EXTRA_BYTES", at + "attribute '" + a.name + "' is described twice");
      }
    }
    a.offset = offset;
    offset += a.size;
    out.push_back(a);
  }
  if (offset > record_length) {
    throw Error(ErrorKind::input, "E_LAS_EXTRA_BYTES",
                at + "its attributes need " + std::to_string(offset) + "-byte records, the file's are " +
                    std::to_string(record_length) + " bytes");
  }
  return out;
}

std::size_t las_min_record_length(std::uint8_t point_format) {
  switch (point_format) {
    case 0: return 20;
    case 1: return 28;
    case 2: return 26;
    case 3: return 34;
    case 6: return 30;
    case 7: return 36;
    case 8: return 38;
    default: return 0;  // 4, 5, 9, 10 carry waveform packets; > 10 is not LAS
  }
}

namespace {

// The format byte and the legacy point count as the header stores them.
struct StoredCounts {
  std::uint8_t raw_format = 0;
  std::uint32_t legacy_count = 0;
};

// The fields every version's header has, from its first bytes `b`.
StoredCounts read_header_fields(const std::vector<std::uint8_t>& b, LasHeader& h) {
  h.file_source_id = get<std::uint16_t>(&b[4]);
  h.global_encoding = get<std::uint16_t>(&b[6]);
  std::memcpy(h.project_guid.data(), &b[8], 16);
  h.version_major = b[24];
  h.version_minor = b[25];
  std::memcpy(h.system_identifier.data(), &b[26], 32);
  std::memcpy(h.generating_software.data(), &b[58], 32);
  h.creation_day = get<std::uint16_t>(&b[90]);
  h.creation_year = get<std::uint16_t>(&b[92]);
  h.header_size = get<std::uint16_t>(&b[94]);
  h.offset_to_points = get<std::uint32_t>(&b[96]);
  h.vlr_count = get<std::uint32_t>(&b[100]);
  const std::uint8_t raw_format = b[104];
  h.record_length = get<std::uint16_t>(&b[105]);
  const std::uint32_t legacy_count = get<std::uint32_t>(&b[107]);
  for (std::size_t i = 0; i < 5; ++i) h.points_by_return[i] = get<std::uint32_t>(&b[111 + 4 * i]);
  for (std::size_t a = 0; a < 3; ++a) {
    h.scale[a] = get<double>(&b[131 + 8 * a]);
    h.offset[a] = get<double>(&b[155 + 8 * a]);
    h.max[a] = get<double>(&b[179 + 16 * a]);
    h.min[a] = get<double>(&b[187 + 16 * a]);
  }
  return {raw_format, legacy_count};
}

// The version, and the header size against it and the file.
void check_version(const std::filesystem::path& path, std::uint64_t file_size, const LasHeader& h) {
  if (h.version_major != 1 || h.version_minor < 2 || h.version_minor > 4) {
    throw malformed(path, 24, "LAS version " + std::to_string(h.version_major) + "." +
                                  std::to_string(h.version_minor) + " is not supported; expected 1.2, 1.3 or 1.4");
  }
  const std::uint16_t min_header =
      h.version_minor == 2 ? kHeaderSize12 : (h.version_minor == 3 ? kHeaderSize13 : kHeaderSize14);
  if (h.header_size < min_header) {
    throw malformed(path, 94, "header size " + std::to_string(h.header_size) + " is too small for LAS 1." +
                                  std::to_string(h.version_minor) + " (expected at least " +
                                  std::to_string(min_header) + ")");
  }
  if (file_size < h.header_size) {
    throw malformed(path, file_size, "truncated LAS header: header size is " + std::to_string(h.header_size) +
                                         " bytes, the file has " + std::to_string(file_size));
  }
}

// The point format (its compression bits cleared in h), the record length
// and the scales and offsets; returns whether the points are compressed.
bool read_point_format(const std::filesystem::path& path, std::uint8_t raw_format, LasHeader& h) {
  // LAZ: bit 7 (or 6, in early LASzip files) set on the format; the
  // laszip VLR, read below, says how.
  const bool compressed = (raw_format & 0xC0) != 0;
  h.point_format = compressed ? static_cast<std::uint8_t>(raw_format & 0x3F) : raw_format;
  const std::size_t min_len = las_min_record_length(h.point_format);
  if (min_len == 0 && compressed) {
    const std::uint8_t f = h.point_format;
    const bool waveform = f == 4 || f == 5 || f == 9 || f == 10;
    throw Error(ErrorKind::input, waveform ? "E_LAZ_UNSUPPORTED" : "E_LAS",
                path.string() + ": byte 104: LAZ point data record format " + std::to_string(f) +
                    (waveform ? std::string(" (waveform packets, ") + (f < 6 ? "WAVEPACKET13" : "WAVEPACKET14") +
                                    " items) is not supported"
                              : std::string(" is unknown")) +
                    "; expected 0, 1, 2, 3, 6, 7 or 8");
  }
  if (min_len == 0) {
    throw malformed(path, 104, "point data record format " + std::to_string(raw_format) +
                                   (raw_format <= 10 ? " (waveform) is not supported" : " is unknown") +
                                   "; expected 0, 1, 2, 3, 6, 7 or 8");
  }
  const std::uint8_t format = h.point_format;
  if (format >= 6 && h.version_minor < 4) {
    throw malformed(path, 104, "point data record format " + std::to_string(format) + " needs LAS 1.4, the file says 1." +
                                   std::to_string(h.version_minor));
  }
  if (h.record_length < min_len) {
    throw malformed(path, 105, "point data record length " + std::to_string(h.record_length) +
                                   " is shorter than format " + std::to_string(format) + "'s " +
                                   std::to_string(min_len) + " bytes");
  }
  for (std::size_t a = 0; a < 3; ++a) {
    if (!(std::isfinite(h.scale[a]) && h.scale[a] > 0.0) || !std::isfinite(h.offset[a])) {
      throw malformed(path, 131 + 8 * a, std::string("scale/offset of ") + "XYZ"[a] +
                                             " must be finite with a positive scale");
    }
  }
  return compressed;
}

// The point count: the legacy one, or LAS 1.4's 64-bit one (and where the
// EVLRs start).
void read_point_count(const std::filesystem::path& path, const std::vector<std::uint8_t>& b, std::uint32_t legacy_count,
                      bool compressed, LasHeader& h) {
  const std::uint8_t format = h.point_format;
  h.point_count = legacy_count;
  if (h.version_minor == 4) {
    h.evlr_start = get<std::uint64_t>(&b[235]);
    h.evlr_count = get<std::uint32_t>(&b[243]);
    const std::uint64_t count64 = get<std::uint64_t>(&b[247]);
    for (std::size_t i = 0; i < 15; ++i) h.points_by_return[i] = get<std::uint64_t>(&b[255 + 8 * i]);
    if (legacy_count != 0 && count64 != legacy_count) {
      throw malformed(path, 107, "legacy point count " + std::to_string(legacy_count) +
                                     " disagrees with the 64-bit point count " + std::to_string(count64));
    }
    // PDAL's COPC writer fills the legacy count of formats 6-8 (equal to
    // the 64-bit one, checked above); LAZ readers accept it, so does this one.
    if (format >= 6 && legacy_count != 0 && !compressed) {
      throw malformed(path, 107, "legacy point count must be 0 for point format " + std::to_string(format));
    }
    h.point_count = count64;
  }
}

// The VLRs between the header and the point data, appended to `vlrs`; the
// laszip VLR kept apart and returned (required when `compressed`).
std::optional<LasVlr> read_vlrs(int fd, const std::filesystem::path& path, std::uint64_t file_size, bool compressed,
                                std::uint8_t raw_format, const LasHeader& h, std::vector<LasVlr>& vlrs) {
  std::optional<LasVlr> laz_vlr;
  // VLRs: between the header and the point data.
  std::uint64_t at = h.header_size;
  if (h.offset_to_points < h.header_size || h.offset_to_points > file_size) {
    throw malformed(path, 96, "offset to point data " + std::to_string(h.offset_to_points) +
                                  " is outside [header size " + std::to_string(h.header_size) + ", file size " +
                                  std::to_string(file_size) + "]");
  }
  for (std::uint32_t i = 0; i < h.vlr_count; ++i) {
    std::uint8_t vh[kVlrHeaderSize];
    if (at + kVlrHeaderSize > h.offset_to_points || !read_at(fd, at, vh, kVlrHeaderSize)) {
      throw malformed(path, at, "VLR " + std::to_string(i + 1) + " of " + std::to_string(h.vlr_count) +
                                    " runs past the start of the point data at byte " +
                                    std::to_string(h.offset_to_points));
    }
    LasVlr v;
    v.file_offset = at;
    v.user_id = fixed_text(vh + 2, 16);
    v.record_id = get<std::uint16_t>(vh + 18);
    const std::uint16_t len = get<std::uint16_t>(vh + 20);
    v.description = fixed_text(vh + 22, 32);
    if (at + kVlrHeaderSize + len > h.offset_to_points) {
      throw malformed(path, at, "VLR " + std::to_string(i + 1) + " ('" + v.user_id + "' " +
                                    std::to_string(v.record_id) + ", " + std::to_string(len) +
                                    " bytes) runs past the start of the point data at byte " +
                                    std::to_string(h.offset_to_points));
    }
    v.data.resize(len);
    if (len && !read_at(fd, at + kVlrHeaderSize, v.data.data(), len)) throw malformed(path, at, "cannot read VLR");
    at += kVlrHeaderSize + len;
    if (is_laz_vlr(v)) {  // kept apart: a compression record is not passed through
      if (compressed && laz_vlr) {
        throw Error(ErrorKind::input, "E_LAZ_VLR",
                    path.string() + ": byte " + std::to_string(v.file_offset) + ": a second laszip VLR (the first is at byte " +
                        std::to_string(laz_vlr->file_offset) + ")");
      }
      laz_vlr = std::move(v);
      continue;
    }
    vlrs.push_back(std::move(v));
  }
  if (compressed && !laz_vlr) {
    throw Error(ErrorKind::input, "E_LAZ_VLR",
                path.string() + ": byte 104: point data record format byte " + std::to_string(raw_format) +
                    " marks compressed (LAZ) points, but there is no laszip VLR ('" + kLazVlrUserId + "' " +
                    std::to_string(kLazVlrRecordId) + ") saying how");
  }
  return laz_vlr;
}

// Point data against the file size (and the EVLRs that follow it); a
// LAZ file's chunk table is checked once the EVLRs are read.
void check_point_data(const std::filesystem::path& path, std::uint64_t file_size, bool compressed, const LasHeader& h) {
  if (compressed) {
    if (h.evlr_count > 0 && (h.evlr_start < h.offset_to_points || h.evlr_start > file_size)) {
      throw malformed(path, 235, "start of the EVLRs " + std::to_string(h.evlr_start) + " is outside [offset to point data " +
                                     std::to_string(h.offset_to_points) + ", file size " + std::to_string(file_size) + "]");
    }
  }
  if (!compressed) {
    const std::uint64_t points_bytes = h.point_count * h.record_length;
    if (h.record_length != 0 && points_bytes / h.record_length != h.point_count) {
      throw malformed(path, 247, "point count " + std::to_string(h.point_count) + " overflows the file size");
    }
    const std::uint64_t points_end = h.offset_to_points + points_bytes;
    const std::uint64_t data_end = h.evlr_count > 0 ? h.evlr_start : file_size;
    if (points_end > file_size) {
      throw malformed(path, file_size, "truncated point data: " + std::to_string(h.point_count) + " points of " +
                                           std::to_string(h.record_length) + " bytes need " +
                                           std::to_string(points_end) + " bytes, the file has " +
                                           std::to_string(file_size));
    }
    if (points_end != data_end) {
      throw malformed(path, points_end, "point count " + std::to_string(h.point_count) + " disagrees with the " +
                                            (h.evlr_count > 0 ? "start of the EVLRs at byte " : "file size ") +
                                            std::to_string(data_end) + ": the points end at byte " +
                                            std::to_string(points_end));
    }
  }
}

// The EVLRs, from the header's start of them, appended to `vlrs`.
void read_evlrs(int fd, const std::filesystem::path& path, std::uint64_t file_size, const LasHeader& h,
                std::vector<LasVlr>& vlrs) {
  std::uint64_t at = h.evlr_start;
  for (std::uint32_t i = 0; i < h.evlr_count; ++i) {
    std::uint8_t eh[kEvlrHeaderSize];
    if (at + kEvlrHeaderSize > file_size || !read_at(fd, at, eh, kEvlrHeaderSize)) {
      throw malformed(path, at, "EVLR " + std::to_string(i + 1) + " of " + std::to_string(h.evlr_count) +
                                    " runs past the end of the file (" + std::to_string(file_size) + " bytes)");
    }
    LasVlr v;
    v.extended = true;
    v.file_offset = at;
    v.user_id = fixed_text(eh + 2, 16);
    v.record_id = get<std::uint16_t>(eh + 18);
    const std::uint64_t len = get<std::uint64_t>(eh + 20);
    v.description = fixed_text(eh + 28, 32);
    if (len > file_size || at + kEvlrHeaderSize + len > file_size) {
      throw malformed(path, at, "EVLR " + std::to_string(i + 1) + " ('" + v.user_id + "' " +
                                    std::to_string(v.record_id) + ", " + std::to_string(len) +
                                    " bytes) runs past the end of the file (" + std::to_string(file_size) +
                                    " bytes)");
    }
    v.data.resize(static_cast<std::size_t>(len));
    if (len && !read_at(fd, at + kEvlrHeaderSize, v.data.data(), v.data.size())) {
      throw malformed(path, at, "cannot read EVLR");
    }
    at += kEvlrHeaderSize + len;
    vlrs.push_back(std::move(v));
  }
}

}  // namespace

LasReader::LasReader(const std::filesystem::path& path) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0) {
    ::close(fd_);
    throw Error(ErrorKind::io, "E_READ", path.string() + ": cannot stat: " + std::strerror(errno));
  }
  try {
    const auto file_size = static_cast<std::uint64_t>(st.st_size);
    std::vector<std::uint8_t> b(kHeaderSize14, 0);
    const std::size_t first = static_cast<std::size_t>(std::min<std::uint64_t>(file_size, kHeaderSize14));
    if (file_size < kHeaderSize12 || !read_at(fd_, 0, b.data(), first)) {
      throw malformed(path, file_size, "truncated LAS header: the file has " + std::to_string(file_size) +
                                           " bytes, a LAS header at least " + std::to_string(kHeaderSize12));
    }
    if (std::memcmp(b.data(), "LASF", 4) != 0) throw malformed(path, 0, "not a LAS file (signature is not 'LASF')");
    LasHeader& h = header_;
    const StoredCounts stored = read_header_fields(b, h);
    check_version(path, file_size, h);
    const bool compressed = read_point_format(path, stored.raw_format, h);
    read_point_count(path, b, stored.legacy_count, compressed, h);
    const std::optional<LasVlr> laz_vlr = read_vlrs(fd_, path, file_size, compressed, stored.raw_format, h, vlrs_);
    check_point_data(path, file_size, compressed, h);
    read_evlrs(fd_, path, file_size, h, vlrs_);
    if (compressed) open_laz(file_size, *laz_vlr);
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

LasReader::~LasReader() {
  if (fd_ >= 0) ::close(fd_);
}

std::optional<std::string> LasReader::wkt() const {
  for (const auto& v : vlrs_) {
    if (v.user_id == "LASF_Projection" && v.record_id == kLasWktRecordId) {
      std::string s(v.data.begin(), v.data.end());
      while (!s.empty() && s.back() == '\0') s.pop_back();
      return s;
    }
  }
  return std::nullopt;
}

std::size_t LasReader::read_records(std::vector<std::uint8_t>& buffer, std::size_t max_points) {
  if (laz_) return read_laz_records(buffer, max_points);
  const std::uint64_t left = header_.point_count - next_point_;
  const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, max_points));
  buffer.resize(n * header_.record_length);
  if (n == 0) return 0;
  const std::uint64_t offset = header_.offset_to_points + next_point_ * header_.record_length;
  if (!read_at(fd_, offset, buffer.data(), buffer.size())) {
    throw Error(ErrorKind::io, "E_READ", path_.string() + ": byte " + std::to_string(offset) +
                                             ": cannot read point records (the file shrank or a read failed)");
  }
  next_point_ += n;
  return n;
}

void LasReader::rewind() {
  next_point_ = 0;
  chunk_next_ = 0;
  chunk_used_ = 0;
  chunk_records_.clear();
}

std::vector<std::uint8_t> encode_las14_header(const LasHeader& h) {
  std::vector<std::uint8_t> b(kHeaderSize14, 0);
  std::memcpy(b.data(), "LASF", 4);
  put(b, 4, h.file_source_id);
  put(b, 6, h.global_encoding);
  std::memcpy(&b[8], h.project_guid.data(), 16);
  b[24] = 1;
  b[25] = 4;
  std::memcpy(&b[26], h.system_identifier.data(), 32);
  std::memcpy(&b[58], h.generating_software.data(), 32);
  put(b, 90, h.creation_day);
  put(b, 92, h.creation_year);
  put(b, 94, kHeaderSize14);
  put(b, 96, h.offset_to_points);
  put(b, 100, h.vlr_count);
  b[104] = h.point_format;
  put(b, 105, h.record_length);
  // Legacy counts: only for formats 0–5 (a LAZ format byte has bit 7 set)
  // and counts that fit 32 bits.
  const bool legacy = (h.point_format & 0x3F) < 6 && h.point_count <= UINT32_MAX;
  put(b, 107, static_cast<std::uint32_t>(legacy ? h.point_count : 0));
  for (std::size_t i = 0; i < 5; ++i) {
    const bool fits = legacy && h.points_by_return[i] <= UINT32_MAX;
    put(b, 111 + 4 * i, static_cast<std::uint32_t>(fits ? h.points_by_return[i] : 0));
  }
  for (std::size_t a = 0; a < 3; ++a) {
    put(b, 131 + 8 * a, h.scale[a]);
    put(b, 155 + 8 * a, h.offset[a]);
    put(b, 179 + 16 * a, h.max[a]);
    put(b, 187 + 16 * a, h.min[a]);
  }
  put(b, 227, std::uint64_t{0});  // no waveform data packets
  put(b, 235, h.evlr_start);
  put(b, 243, h.evlr_count);
  put(b, 247, h.point_count);
  for (std::size_t i = 0; i < 15; ++i) put(b, 255 + 8 * i, h.points_by_return[i]);
  return b;
}

LasWriter::LasWriter(std::ostream& out, const LasHeader& header, std::vector<LasVlr> vlrs, std::vector<LasVlr> evlrs,
                     std::string name, LasCompression compression)
    : out_(out), header_(header), evlrs_(std::move(evlrs)), name_(std::move(name)) {
  std::erase_if(vlrs, is_laz_vlr);
  if (compression.laz) {
    laz_ = LazVlr::for_format(header_.point_format, header_.record_length, compression.chunk_points);
    LasVlr v;
    v.user_id = kLazVlrUserId;
    v.record_id = kLazVlrRecordId;
    v.description = "LASzip format, by geoanchor";
    v.data = laz_->bytes();
    vlrs.push_back(std::move(v));
    encoder_.emplace(*laz_);
  }
  header_.version_major = 1;
  header_.version_minor = 4;
  header_.header_size = kHeaderSize14;
  header_.global_encoding = static_cast<std::uint16_t>(header_.global_encoding & ~0x6u);  // no waveform packets
  header_.vlr_count = static_cast<std::uint32_t>(vlrs.size());
  header_.point_count = 0;
  header_.evlr_start = 0;
  header_.evlr_count = static_cast<std::uint32_t>(evlrs_.size());
  std::uint64_t offset = kHeaderSize14;
  for (const auto& v : vlrs) {
    if (v.data.size() > UINT16_MAX) {
      throw Error(ErrorKind::input, "E_LAS", name_ + ": VLR '" + v.user_id + "' " + std::to_string(v.record_id) +
                                                 " holds " + std::to_string(v.data.size()) +
                                                 " bytes, more than a VLR can (65535)");
    }
    offset += kVlrHeaderSize + v.data.size();
  }
  if (offset > UINT32_MAX) throw Error(ErrorKind::input, "E_LAS", name_ + ": VLRs exceed 4 GiB");
  header_.offset_to_points = static_cast<std::uint32_t>(offset);
  LasHeader stored = header_;
  if (laz_) stored.point_format = static_cast<std::uint8_t>(stored.point_format | 0x80);
  const auto h = encode_las14_header(stored);
  out_.write(reinterpret_cast<const char*>(h.data()), static_cast<std::streamsize>(h.size()));
  for (const auto& v : vlrs) {
    std::vector<std::uint8_t> vh(kVlrHeaderSize, 0);
    put_text(vh, 2, v.user_id, 16);
    put(vh, 18, v.record_id);
    put(vh, 20, static_cast<std::uint16_t>(v.data.size()));
    put_text(vh, 22, v.description, 32);
    out_.write(reinterpret_cast<const char*>(vh.data()), static_cast<std::streamsize>(vh.size()));
    out_.write(reinterpret_cast<const char*>(v.data.data()), static_cast<std::streamsize>(v.data.size()));
  }
  if (laz_) {
    // The chunk table's offset; until finish() it points at itself, which
    // tells a reader that the table was never written.
    const std::uint64_t self = header_.offset_to_points;
    out_.write(reinterpret_cast<const char*>(&self), sizeof self);
  }
}

LasWriter::~LasWriter() = default;

void LasWriter::write_records(const std::uint8_t* data, std::size_t n) {
  if (!laz_) {
    out_.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(n * header_.record_length));
    written_ += n;
    return;
  }
  const std::size_t len = header_.record_length;
  const std::size_t per_chunk = laz_->chunk_size;
  while (n > 0) {
    const std::size_t take = std::min(n, per_chunk - gathered_.size() / len);
    gathered_.insert(gathered_.end(), data, data + take * len);
    data += take * len;
    n -= take;
    if (gathered_.size() / len == per_chunk) flush_gathered();
  }
}

void LasWriter::restart(const std::array<double, 3>& offset) {
  if (laz_) throw std::logic_error(name_ + ": a LAZ output cannot be rewritten in place; write it again to a new stream");
  header_.offset = offset;
  written_ = 0;
  out_.seekp(static_cast<std::streamoff>(header_.offset_to_points));
}

void LasWriter::finish(const std::array<std::uint64_t, 15>& points_by_return, const std::array<double, 3>& min,
                       const std::array<double, 3>& max) {
  std::uint64_t points_end = header_.offset_to_points + written_ * header_.record_length;
  if (laz_) points_end = finish_laz_chunks();
  header_.point_count = written_;
  header_.points_by_return = points_by_return;
  header_.min = min;
  header_.max = max;
  header_.evlr_start = evlrs_.empty() ? 0 : points_end;
  for (const auto& v : evlrs_) {
    std::vector<std::uint8_t> eh(kEvlrHeaderSize, 0);
    put_text(eh, 2, v.user_id, 16);
    put(eh, 18, v.record_id);
    put(eh, 20, static_cast<std::uint64_t>(v.data.size()));
    put_text(eh, 28, v.description, 32);
    out_.write(reinterpret_cast<const char*>(eh.data()), static_cast<std::streamsize>(eh.size()));
    out_.write(reinterpret_cast<const char*>(v.data.data()), static_cast<std::streamsize>(v.data.size()));
  }
  LasHeader stored = header_;
  if (laz_) stored.point_format = static_cast<std::uint8_t>(stored.point_format | 0x80);
  const auto h = encode_las14_header(stored);
  out_.seekp(0);
  out_.write(reinterpret_cast<const char*>(h.data()), static_cast<std::streamsize>(h.size()));
  out_.seekp(0, std::ios::end);
  if (!out_) throw Error(ErrorKind::io, "E_WRITE", name_ + ": writing the LAS file failed (disk full or I/O error)");
}

}  // namespace geoanchor::io
