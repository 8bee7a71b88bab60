// DynAdjust's DynaML station and measurement files (XML), read as a stream
// with expat: no tree of the whole file is built.
//
// The format as DynaML.xsd (DynAdjust, sampleData/DynaML.xsd, v1.0.2) and
// DynAdjust's own reader define it (docs/network-format.md lists what is
// read and how):
//  - <DnaXmlFormat referenceframe="GDA2020" epoch="dd.mm.yyyy"> holds
//    <DnaStation> and <DnaMeasurement> elements in any order;
//  - a station's Constraints are three letters C/F: latitude, longitude,
//    height for Type LLH, otherwise east, north, up (UTM, LLh) or X, Y, Z
//    (XYZ); LLH and UTM heights are orthometric, LLh ellipsoidal; latitudes
//    and longitudes are packed sexagesimal DDD.MMSSsss;
//  - angles are packed sexagesimal, their standard deviations arc-seconds;
//    distances and heights metres;
//  - a GNSS baseline's covariance is the upper triangle SigmaXX … SigmaZZ
//    (m²); in a cluster (X, Y) item i carries the blocks cov(i, j) for
//    j = i + 1, …, n − 1 as GPSCovariance / PointCovariance m11 … m33
//    (m_rc: component r of i, component c of j);
//  - Vscale multiplies a GNSS covariance; Pscale, Lscale, Hscale its
//    variances along latitude, longitude and height at the first station;
//  - an empty <Ignore/> is a measurement in use, any text one left out;
//  - a direction set's parent gives the reference object (Second, Value,
//    StdDev) and its <Directions> the other targets.
//
// This file reads a file, whole or in parts on threads; the reader itself
// is network_dynaml_reader.hpp (elements, stations, measurements).

#include <algorithm>
#include <cstddef>
#include <initializer_list>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "geoanchor/base/error.hpp"
#include "network/network_builder.hpp"
#include "network/network_dynaml_reader.hpp"
#include "network/network_readers.hpp"

namespace geoanchor::io::detail {

void dynaml::warn_approximate_heights(std::string_view source, std::size_t count, geodesy::Network& into) {
  if (count == 0) return;
  into.warnings.push_back(std::string(source) + ": " + std::to_string(count) +
                          " free station(s) have orthometric heights and there is no --geoid: each starts the iteration "
                          "at h = H (metres off where N is metres; their adjusted heights do not depend on it)");
}

void dynaml::require_ellipsoidal(std::string_view source, const char* format, geodesy::Network& into) {
  if (!into.stations.empty() && into.space != geodesy::NetworkSpace::ellipsoidal) {
    throw Error(ErrorKind::input, "E_NETWORK", std::string(source) + ": " + format + " is a network on the ellipsoid; the other inputs are local");
  }
  into.space = geodesy::NetworkSpace::ellipsoidal;
}

namespace {

using dynaml::Reader;
using dynaml::warn_approximate_heights;

// The line breaks in `t` as expat counts them (XML's end-of-line rule): LF,
// CR LF and a CR alone are one each. A part's line offset counted in LFs
// alone put every line after a lone CR elsewhere than one reading does.
std::ptrdiff_t xml_line_breaks(std::string_view t) {
  std::ptrdiff_t n = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] == '\n' || (t[i] == '\r' && (i + 1 == t.size() || t[i + 1] != '\n'))) ++n;
  }
  return n;
}

// A large file read in parts on threads (expat is one thread; a 10⁵-station
// measurement file is 180 MB of XML). The parts are cut where a top-level
// element (<DnaStation>, <DnaMeasurement>) starts; each is read as a
// document of its own (the file's prologue and root start tag before it,
// the root's end tag after it) into a network of its own, and the networks
// are joined in the file's order by station name: the same network as one
// reading. A cut that fell inside a comment or CDATA section leaves a part
// that is not well-formed; then, or on any other error, nothing of the
// parts is kept and the caller reads the file whole, which reports the
// error as it always does. False: not read here.
bool read_dynaml_in_parts(std::string_view text, std::string_view source, geodesy::Network& into, const NetworkReadOptions& options) {
  if (options.geoid) return false;  // (PROJ's grids are for one thread)
  const std::size_t cores = std::max(1u, std::thread::hardware_concurrency());
  const std::size_t wanted = std::min<std::size_t>(cores, options.dynaml_part_bytes ? text.size() / options.dynaml_part_bytes : 1);
  if (wanted < 2) return false;
  // The root element's start tag (past the prologue; attribute values may
  // hold '>', quotes not).
  const std::size_t root = text.find("<DnaXmlFormat");
  if (root == std::string_view::npos || text.substr(0, root).find("<!DOCTYPE") != std::string_view::npos) return false;
  std::size_t root_end = root;
  char quote = 0;
  for (; root_end < text.size(); ++root_end) {
    const char c = text[root_end];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '>') {
      break;
    }
  }
  if (root_end >= text.size() || text[root_end - 1] == '/') return false;
  ++root_end;
  const std::string_view prologue = text.substr(0, root_end);
  // The cuts: at the first top-level element at or past each share.
  std::vector<std::size_t> cut{root_end};
  for (std::size_t k = 1; k < wanted; ++k) {
    std::size_t at = std::max(cut.back() + 1, root_end + k * (text.size() - root_end) / wanted);
    for (at = text.find("<Dna", at); at != std::string_view::npos; at = text.find("<Dna", at + 1)) {
      const std::string_view rest = text.substr(at + 4);
      if (rest.substr(0, 12) == "Measurement>" || rest.substr(0, 8) == "Station>") break;
    }
    if (at == std::string_view::npos) break;
    cut.push_back(at);
  }
  cut.push_back(text.size());
  const std::size_t parts = cut.size() - 1;
  if (parts < 2) return false;
  const std::ptrdiff_t prologue_lines = xml_line_breaks(prologue);
  std::vector<std::ptrdiff_t> line_before(parts, 0);  // line breaks before each part
  for (std::size_t k = 1; k < parts; ++k) {
    const std::size_t from = k == 1 ? 0 : cut[k - 1];
    line_before[k] = line_before[k - 1] + xml_line_breaks(text.substr(from, cut[k] - from));
  }
  struct Part {
    geodesy::Network net;
    std::size_t approximate_heights = 0;
    bool ok = false;
  };
  std::vector<Part> read(parts);
  const auto read_part = [&](std::size_t k) {
    Part& part = read[k];
    part.net.space = geodesy::NetworkSpace::ellipsoidal;
    part.net.frame = into.frame;
    part.net.ellipsoid = into.ellipsoid;
    part.net.ellipsoid_stated = into.ellipsoid_stated;
    try {
      Reader reader(source, part.net, options);
      constexpr std::string_view kEnd = "</DnaXmlFormat>";
      const std::string_view body = text.substr(cut[k], cut[k + 1] - cut[k]);
      // Room for its measurements at once (a few hundred bytes each, moved
      // again at every doubling otherwise): one per <DnaMeasurement>, a
      // hint (a direction set is several).
      {
        const std::string_view own = k == 0 ? text.substr(0, cut[1]) : body;
        std::size_t count = 0;
        for (auto at = own.find("<DnaMeasurement"); at != std::string_view::npos; at = own.find("<DnaMeasurement", at + 1)) ++count;
        part.net.measurements.reserve(count);
      }
      if (k == 0) {
        reader.parse_part({text.substr(0, cut[1]), kEnd}, 0, true);
      } else if (k + 1 < parts) {
        reader.parse_part({prologue, body, kEnd}, line_before[k] - prologue_lines, false);
      } else {
        reader.parse_part({prologue, body}, line_before[k] - prologue_lines, false);
      }
      part.approximate_heights = reader.approximate_heights();
      part.ok = true;
    } catch (...) {
      part.ok = false;  // read whole instead, for the error as it is reported there
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(parts);
  for (std::size_t k = 1; k < parts; ++k) {
    try {
      pool.emplace_back(read_part, k);
    } catch (...) {  // std::system_error, std::bad_alloc: never unwind past running threads
      read_part(k);
    }
  }
  read_part(0);
  for (auto& t : pool) t.join();
  if (!std::all_of(read.begin(), read.end(), [](const Part& p) { return p.ok; })) return false;

  // Joined in order: each part's stations by name (defined or referenced,
  // in the order they came), then its measurements and direction sets.
  geodesy::Network joined = into;
  try {
    NetworkBuilder builder(joined);
    std::size_t approximate = 0, measurements = joined.measurements.size();
    for (std::size_t k = 0; k < parts; ++k) measurements += read[k].net.measurements.size();
    joined.measurements.reserve(measurements);  // moved in once, not again at each doubling
    for (std::size_t k = 0; k < parts; ++k) {
      Part& part = read[k];
      if (k == 0 && !joined.frame) {
        joined.frame = part.net.frame;
        joined.ellipsoid = part.net.ellipsoid;
        joined.ellipsoid_stated = part.net.ellipsoid_stated;
      }
      std::vector<std::size_t> station(part.net.stations.size());
      for (std::size_t i = 0; i < part.net.stations.size(); ++i) {
        const geodesy::NetworkStation& s = part.net.stations[i];
        station[i] = s.defined ? builder.define(s.id, s.position, s.constraint, s.source) : builder.reference(s.id, s.source);
      }
      const std::size_t sets = joined.direction_sets.size();
      for (auto d : part.net.direction_sets) {
        d.station = station[d.station];
        joined.direction_sets.push_back(std::move(d));
      }
      for (auto& m : part.net.measurements) {
        for (auto& st : m.stations) st = station[st];
        if (m.set) *m.set += sets;
        joined.measurements.push_back(std::move(m));
      }
      joined.warnings.insert(joined.warnings.end(), part.net.warnings.begin(), part.net.warnings.end());
      approximate += part.approximate_heights;
    }
    warn_approximate_heights(source, approximate, joined);
  } catch (const Error&) {
    return false;  // (a station defined twice, differently: read whole, for the message as it is)
  }
  into = std::move(joined);
  return true;
}

}  // namespace

void read_dynaml(std::string_view text, std::string_view source, geodesy::Network& into, const NetworkReadOptions& options) {
  dynaml::require_ellipsoidal(source, "DynaML", into);
  if (read_dynaml_in_parts(text, source, into, options)) return;
  Reader reader(source, into, options);
  reader.parse(text);
  warn_approximate_heights(source, reader.approximate_heights(), into);
}

}  // namespace geoanchor::io::detail
