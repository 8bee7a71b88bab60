// PLY tiles through a PointChain: ASCII or binary little-endian, the vertex
// element first, x/y/z as float or double (float only for map-local ENU/NED
// offsets). The output writes x, y, z as double; every other vertex
// property and every later element pass through unchanged.

#include <charconv>
#include <cstring>
#include <fstream>
#include <sstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/float32.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/tile/tile_metadata.hpp"
#include "tile/tile_common.hpp"

namespace geoanchor::io {
namespace {

struct Property {
  std::string type;  // as written
  std::string name;
  std::size_t size = 0;
};

std::size_t scalar_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

struct PlyHeader {
  bool binary = false;
  std::vector<std::string> lines;  // as read, without the line ends
  std::size_t element_line = 0;    // index of "element vertex N"
  std::uint64_t vertices = 0;
  std::vector<Property> properties;
  std::size_t ix = 0, iy = 0, iz = 0;  // property indices
  bool coordinates_float32 = false;
  std::size_t record_size = 0;
  std::uint64_t data_offset = 0;  // bytes
  std::size_t header_lines = 0;
};

[[noreturn]] void fail(const std::string& source, const std::string& where, const std::string& problem) {
  throw Error(ErrorKind::input, "E_PLY", source + ":" + where + ": " + problem);
}

PlyHeader read_header(std::istream& in, const std::string& source) {
  PlyHeader h;
  std::string line;
  bool in_vertex = false, seen_element = false, ended = false;
  std::size_t line_no = 0;
  std::uint64_t offset = 0;
  while (std::getline(in, line)) {
    ++line_no;
    offset += line.size() + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    h.lines.push_back(line);
    const std::string where = std::to_string(line_no);
    if (line_no == 1) {
      if (line != "ply") fail(source, where, "not a PLY file (the first line is not 'ply')");
      continue;
    }
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "format") {
      std::string fmt, version;
      words >> fmt >> version;
      if (fmt == "ascii") {
        h.binary = false;
      } else if (fmt == "binary_little_endian") {
        h.binary = true;
      } else {
        fail(source, where, "format '" + fmt + "' is not supported; expected ascii or binary_little_endian");
      }
      if (version != "1.0") fail(source, where, "format version '" + version + "'; expected 1.0");
    } else if (key == "comment" || key == "obj_info") {
    } else if (key == "element") {
      std::string name;
      std::string count;
      words >> name >> count;
      if (!seen_element && name != "vertex") fail(source, where, "the first element is '" + name + "'; expected vertex");
      if (!seen_element) {
        std::uint64_t n = 0;
        const auto res = std::from_chars(count.data(), count.data() + count.size(), n);
        if (res.ec != std::errc() || res.ptr != count.data() + count.size()) {
          fail(source, where, "vertex count '" + count + "' is not a non-negative integer");
        }
        h.vertices = n;
        h.element_line = h.lines.size() - 1;
        in_vertex = true;
      } else {
        in_vertex = false;
      }
      seen_element = true;
    } else if (key == "property") {
      if (!seen_element) fail(source, where, "a property before any element");
      if (!in_vertex) continue;
      Property p;
      words >> p.type;
      if (p.type == "list") fail(source, where, "list properties in the vertex element are not supported");
      words >> p.name;
      p.size = scalar_size(p.type);
      if (p.size == 0) fail(source, where, "property type '" + p.type + "' unknown");
      h.properties.push_back(p);
    } else if (key == "end_header") {
      ended = true;
      break;
    } else {
      fail(source, where, "unknown header keyword '" + key + "'");
    }
  }
  if (!ended) fail(source, std::to_string(line_no), "the header has no end_header line");
  h.header_lines = line_no;
  h.data_offset = offset;
  bool fx = false, fy = false, fz = false;
  for (std::size_t i = 0; i < h.properties.size(); ++i) {
    const auto& p = h.properties[i];
    if (p.name == "x") h.ix = i, fx = true;
    if (p.name == "y") h.iy = i, fy = true;
    if (p.name == "z") h.iz = i, fz = true;
    h.record_size += p.size;
  }
  if (!fx || !fy || !fz) fail(source, std::to_string(h.element_line + 1), "the vertex element lacks x, y or z");
  for (std::size_t i : {h.ix, h.iy, h.iz}) {
    const auto& t = h.properties[i].type;
    if (t == "float" || t == "float32") {
      h.coordinates_float32 = true;
    } else if (t != "double" && t != "float64") {
      fail(source, std::to_string(h.element_line + 1), "property " + h.properties[i].name + " is " + t +
                                                            "; coordinates must be float or double");
    }
  }
  return h;
}

std::size_t offset_of(const PlyHeader& h, std::size_t index) {
  std::size_t o = 0;
  for (std::size_t i = 0; i < index; ++i) o += h.properties[i].size;
  return o;
}

double read_coordinate(const std::uint8_t* p, const Property& prop) {
  if (prop.size == 4) {
    float f;
    std::memcpy(&f, p, 4);
    return f;
  }
  double d;
  std::memcpy(&d, p, 8);
  return d;
}

// float32 x/y/z only for map-local ENU/NED offsets.
void check_float32(const PlyHeader& h, const std::string& source, const TileApplyOptions& o) {
  if (h.coordinates_float32 && o.file_in) {
    fail(source, std::to_string(h.element_line + 1),
         "float32 x/y/z hold coordinates of a CRS; float32 is accepted only for map-local ENU/NED offsets");
  }
  if (h.coordinates_float32 && o.from.kind != CoordinateKind::enu && o.from.kind != CoordinateKind::ned) {
    fail(source, std::to_string(h.element_line + 1),
         "float32 x/y/z hold " + kind_name(o.from) +
             " coordinates; float32 is accepted only for map-local ENU/NED offsets (its step is 0.5 m at ECEF "
             "magnitudes)");
  }
}

void write_header(const PlyHeader& h, std::ostream& out) {
  // Header: the same, with x, y, z as double.
  for (std::size_t i = 0; i < h.lines.size(); ++i) {
    std::string line = h.lines[i];
    if (i > h.element_line && i <= h.element_line + h.properties.size()) {
      const std::size_t k = i - h.element_line - 1;
      const auto& p = h.properties[k];
      if (k == h.ix || k == h.iy || k == h.iz) line = "property double " + p.name;
    }
    if (i == 1) line = h.binary ? "format binary_little_endian 1.0" : "format ascii 1.0";
    out << line << '\n';
  }
}

}  // namespace

TileApplyResult apply_ply_tile(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                               const PointChain& chain, const TileApplyOptions& o) {
  std::ifstream file(in, std::ios::binary);
  if (!file) throw Error(ErrorKind::io, "E_READ", in.string() + ": cannot open");
  const std::string source = in.string();
  const PlyHeader h = read_header(file, source);
  check_float32(h, source, o);
  write_header(h, out);
  TileApplyResult r;
  r.storage = "float64";
  detail::Bounds in_bounds, out_bounds;
  UtmBandTally band_in, band_out;
  const bool geo_in = detail::lon_first_in_files(o.from);
  const bool geo_out = detail::lon_first_in_files(o.to);
  const std::size_t chunk = std::max<std::size_t>(o.chunk_points, 1);
  std::vector<double> x(chunk), y(chunk), z(chunk);
  const std::size_t coord[3] = {h.ix, h.iy, h.iz};

  auto transform = [&](std::size_t n, const std::string& where_first) {
    std::span<double> a(geo_in ? y.data() : x.data(), n), b(geo_in ? x.data() : y.data(), n), c(z.data(), n);
    in_bounds.add(a, b, c);
    auto vertex = [&](std::size_t i) { return "vertex " + std::to_string(r.points + i + 1); };
    const ChainReport report = detail::move_points(chain, o, a, b, c, nullptr, vertex);
    if (const std::size_t bad = detail::first_non_finite(a, b, c); bad < n) {
      throw Error(ErrorKind::input, "E_TRANSFORM",
                  source + ": " + vertex(bad) + " (of the chunk from " + where_first +
                      ") has no finite position in the output frame" + detail::refusal_reason(report, bad) +
                      "; nothing was written");
    }
    if (report.input_band.points) band_in.absorb(report.input_band, vertex(report.input_band.worst_index));
    if (report.output_band.points) band_out.absorb(report.output_band, vertex(report.output_band.worst_index));
    out_bounds.add(geo_out ? b : a, geo_out ? a : b, c);
  };

  if (h.binary) {
    std::size_t out_size = 0;
    for (std::size_t i = 0; i < h.properties.size(); ++i) {
      out_size += (i == h.ix || i == h.iy || i == h.iz) ? 8 : h.properties[i].size;
    }
    std::vector<std::uint8_t> buf(chunk * h.record_size), obuf(chunk * out_size);
    std::uint64_t left = h.vertices;
    while (left > 0) {
      const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, chunk));
      file.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(n * h.record_size));
      if (static_cast<std::size_t>(file.gcount()) != n * h.record_size) {
        const std::uint64_t at = h.data_offset + r.points * h.record_size + static_cast<std::uint64_t>(file.gcount());
        throw Error(ErrorKind::input, "E_PLY",
                    source + ": byte " + std::to_string(at) + ": truncated vertex data: " + std::to_string(h.vertices) +
                        " vertices of " + std::to_string(h.record_size) + " bytes expected");
      }
      double* dst[3] = {x.data(), y.data(), z.data()};
      for (std::size_t k = 0; k < 3; ++k) {
        const std::size_t off = offset_of(h, coord[k]);
        for (std::size_t i = 0; i < n; ++i) dst[k][i] = read_coordinate(&buf[i * h.record_size + off], h.properties[coord[k]]);
      }
      if (const std::size_t bad = detail::first_non_finite({x.data(), n}, {y.data(), n}, {z.data(), n}); bad < n) {
        throw Error(ErrorKind::input, "E_PLY",
                    source + ": byte " + std::to_string(h.data_offset + (r.points + bad) * h.record_size) + ": vertex " +
                        std::to_string(r.points + bad + 1) + " has a non-finite coordinate");
      }
      transform(n, "byte " + std::to_string(h.data_offset + r.points * h.record_size));
      for (std::size_t i = 0; i < n; ++i) {
        const std::uint8_t* s = &buf[i * h.record_size];
        std::uint8_t* d = &obuf[i * out_size];
        for (std::size_t p = 0; p < h.properties.size(); ++p) {
          if (p == h.ix || p == h.iy || p == h.iz) {
            const double v = p == h.ix ? x[i] : p == h.iy ? y[i] : z[i];
            std::memcpy(d, &v, 8);
            d += 8;
          } else {
            std::memcpy(d, s, h.properties[p].size);
            d += h.properties[p].size;
          }
          s += h.properties[p].size;
        }
      }
      out.write(reinterpret_cast<const char*>(obuf.data()), static_cast<std::streamsize>(n * out_size));
      r.points += n;
      left -= n;
      if (o.progress) o.progress(r.points);
    }
  } else {
    std::vector<std::vector<std::string>> tokens(chunk);
    std::vector<std::size_t> lines(chunk);
    std::string line;
    std::size_t line_no = h.header_lines;
    std::uint64_t left = h.vertices;
    while (left > 0) {
      const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, chunk));
      for (std::size_t i = 0; i < n; ++i) {
        if (!std::getline(file, line)) {
          fail(source, std::to_string(line_no + 1), "truncated: " + std::to_string(h.vertices) + " vertices expected, " +
                                                       std::to_string(r.points + i) + " found");
        }
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        auto& t = tokens[i];
        t.clear();
        std::istringstream words(line);
        for (std::string w; words >> w;) t.push_back(w);
        if (t.size() != h.properties.size()) {
          fail(source, std::to_string(line_no), std::to_string(t.size()) + " values; the vertex element has " +
                                                    std::to_string(h.properties.size()) + " properties");
        }
        double* dst[3] = {&x[i], &y[i], &z[i]};
        for (std::size_t k = 0; k < 3; ++k) {
          const auto v = parse_finite_double(t[coord[k]]);
          if (!v) {
            fail(source, std::to_string(line_no),
                 h.properties[coord[k]].name + "=" + t[coord[k]] + ": not a finite number");
          }
          *dst[k] = h.properties[coord[k]].size == 4 ? geodesy::round_to_float32(*v) : *v;
        }
        lines[i] = line_no;
      }
      transform(n, "line " + std::to_string(lines[0]));
      for (std::size_t i = 0; i < n; ++i) {
        auto& t = tokens[i];
        t[h.ix] = format_shortest(x[i]);
        t[h.iy] = format_shortest(y[i]);
        t[h.iz] = format_shortest(z[i]);
        for (std::size_t p = 0; p < t.size(); ++p) out << (p ? " " : "") << t[p];
        out << '\n';
      }
      r.points += n;
      left -= n;
      if (o.progress) o.progress(r.points);
    }
  }
  // Later elements (faces, ...) pass through byte for byte.
  // (operator<< of an empty streambuf sets failbit, hence the peek.)
  if (file.peek() != std::char_traits<char>::eof()) out << file.rdbuf();
  if (!out) throw Error(ErrorKind::io, "E_WRITE", out_name + ": write failed");
  detail::set_bounds(r, in_bounds, out_bounds);
  detail::add_band_warnings(r, source, band_in, band_out);
  return r;
}

}  // namespace geoanchor::io
