// What frame and coordinates a tile is in: its sidecar, the LAS file's WKT
// or GeoTIFF keys, a CSV's '# crs' comment, a vector map's own statement,
// or the --from-* flags; the flags checked against what the tile states.
#include "geoanchor/workflow/tile_plan.hpp"

#include <cmath>
#include <fstream>

#include "geoanchor/base/error.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/control/crs_csv.hpp"
#include "geoanchor/io/csv.hpp"
#include "geoanchor/las/las.hpp"
#include "geoanchor/io/tile/las_geotiff.hpp"
#include "geoanchor/io/vector/vector_map.hpp"
#include "geoanchor/workflow/value_text.hpp"
#include "tile_plan_frames.hpp"

namespace geoanchor::workflow {
namespace {

namespace fs = std::filesystem;
using detail::two_d;
using detail::with_epoch;
using geodesy::DecimalYear;
using geodesy::Frame;
using io::ArrayFrame;
using io::CoordinateKind;
using io::TileMetadata;

// Origins given twice (flag and sidecar) agree when they name the same
// point to well below a millimetre.
constexpr double kSameOriginDeg = 1e-10;  // ≈ 0.01 mm
constexpr double kSameOriginM = 1e-5;

// What a tile's stated CRS and --crs say together, or nullopt when they
// contradict each other. --crs may restate the CRS or state it less fully
// (its horizontal part, no epoch), or complete it: the heights of a 2-D CRS
// (the same CRS in 3-D, or a compound CRS with it as the horizontal part)
// and the coordinate epoch of a dynamic one. Compared by PROJ, never by name.
std::optional<io::Crs> reconcile_crs(const io::Crs& stated, const io::Crs& flag) {
  if (stated.epoch() && flag.epoch() && stated.epoch()->year != flag.epoch()->year) return std::nullopt;
  const auto epoch = stated.epoch() ? stated.epoch() : flag.epoch();
  auto at_epoch = [&](const io::Crs& c) {
    return epoch && !c.epoch() && c.description().dynamic ? c.at_epoch(*epoch, "--crs") : c;
  };
  const io::Crs s = at_epoch(stated), f = at_epoch(flag);
  if (s.same_as(f)) return s;
  if (two_d(s) && !two_d(f) && f.horizontal("--crs").same_as(s)) return f;
  if (!two_d(s) && two_d(f) && s.horizontal("--crs").same_as(f)) return s;
  return std::nullopt;
}

bool same_origin(const geodesy::LocalOrigin& a, const geodesy::LocalOrigin& b) {
  return std::abs(a.point.lat.deg() - b.point.lat.deg()) < kSameOriginDeg &&
         std::abs(a.point.lon.deg() - b.point.lon.deg()) < kSameOriginDeg &&
         std::abs(a.point.h.m - b.point.h.m) < kSameOriginM;
}

}  // namespace

// What the flags say about a tile with no sidecar and no WKT.
TileMetadata TilePlanner::input_metadata(TilePlan& p) const {
  if (io::is_vector_map(p.format)) return vector_map_metadata(p);
  const std::string tile = p.input.string();
  std::optional<TileMetadata> side, wkt;
  const fs::path side_path = io::sidecar_path(p.input);
  std::error_code ec;
  if (fs::exists(side_path, ec)) side = io::read_tile_metadata(side_path);
  std::optional<std::string> geotiff_keys;
  if (io::is_las_family(p.format)) read_las_crs(p, side, side_path, wkt, geotiff_keys);
  std::optional<TileMetadata> stated;  // a CSV's '# crs = …' comments
  if (p.format == io::TileFormat::csv) {
    std::ifstream f(p.input, std::ios::binary);
    if (!f) throw Error(ErrorKind::io, "E_READ", tile + ": cannot open");
    const io::CsvReader reader(f, tile);
    p.csv_header = reader.header();
    p.csv_comments = reader.leading_comments();
    if (auto c = io::crs_from_comments(p.csv_comments, tile)) {
      stated = io::tile_metadata_from_crs(std::move(*c), tile);
      stated->storage = "float64";
    }
  }
  if (side && stated) {
    const std::string diff = io::describe_mismatch(*side, side_path.string(), *stated, tile + " '# crs' comment");
    if (!diff.empty()) {
      throw Error(ErrorKind::input, "E_FRAME_CONFLICT", tile + ": the sidecar and the file's '# crs' comment disagree: " + diff);
    }
  }
  if (side && wkt) {
    // A WKT written by another tool may name the realization without the
    // coordinate epoch: the sidecar supplies it.
    if (wkt->frame && side->frame && !wkt->frame->epoch() && side->frame->epoch() &&
        wkt->frame->name() == side->frame->name()) {
      wkt->frame = side->frame;
    }
    if (wkt->crs && side->crs && !wkt->crs->epoch() && side->crs->epoch() &&
        side->crs->description().dynamic) {
      *wkt = io::tile_metadata_from_crs(wkt->crs->at_epoch(*side->crs->epoch(), tile + " WKT"), tile);
    }
    const std::string diff = io::describe_mismatch(*side, side_path.string(), *wkt, tile + " WKT");
    if (!diff.empty()) {
      throw Error(ErrorKind::input, "E_FRAME_CONFLICT",
                  tile + ": the sidecar and the LAS " + (geotiff_keys ? "GeoTIFF keys " + *geotiff_keys : std::string("WKT")) +
                      " disagree: " + diff);
    }
  }
  if (side) {
    p.in_frame_source = "sidecar " + side_path.string();
    check_flags_against(*side, p, tile);
    return *side;
  }
  if (wkt && !wkt->frame && !wkt->crs) {
    // A datum geoanchor cannot name: --from-frame names it, and is recorded.
    if (!from_frame_) {
      throw Error(ErrorKind::input, "E_FRAME_UNKNOWN",
                  tile + ": the LAS WKT's datum '" + wkt->wkt_datum +
                      "' is not a frame geoanchor can name; give --from-frame NAME@EPOCH or a sidecar");
    }
    wkt->frame = from_frame_;
    p.in_frame_source = "LAS WKT (datum '" + wkt->wkt_datum + "' named by --from-frame)";
    check_flags_against(*wkt, p, tile);
    return *wkt;
  }
  if (wkt) {
    p.in_frame_source = geotiff_keys ? "LAS GeoTIFF keys " + *geotiff_keys : std::string("LAS WKT");
    check_flags_against(*wkt, p, tile);
    return *wkt;
  }
  if (stated) {
    p.in_frame_source = "'# crs' comment";
    check_flags_against(*stated, p, tile);
    return *stated;
  }
  if (o_.crs) {
    TileMetadata m = io::tile_metadata_from_crs(io::Crs::parse(*o_.crs, "--crs"), tile);
    m.storage = io::is_las_family(p.format) ? "int32_scaled" : "float64";
    p.in_frame_source = "--crs";
    return m;
  }
  return metadata_from_flags(p, tile, side_path);
}

void TilePlanner::read_las_crs(TilePlan& p, const std::optional<TileMetadata>& side, const fs::path& side_path,
                               std::optional<TileMetadata>& wkt, std::optional<std::string>& geotiff_keys) const {
  const std::string tile = p.input.string();
  io::LasReader reader(p.input);
  p.las_points = reader.header().point_count;
  if (const auto w = reader.wkt()) {
    // A sidecar says how the WKT is read (the sidecar of geoanchor's own
    // coordinates beside the WKT geoanchor wrote for them); without one,
    // where a CRS is asked for, the WKT is read as one (PROJ moves it),
    // else as geoanchor's own coordinates where it can be.
    const bool as_crs = side ? side->crs.has_value() : (o_.crs || o_.to_crs);
    wkt = as_crs ? io::tile_metadata_from_wkt_as_crs(*w, tile) : io::tile_metadata_from_wkt(*w, tile);
  } else {
    // LAS 1.2-1.3 (and 1.4 formats 0-5) state their CRS as GeoTIFF keys:
    // read as the WKT of the CRS they name would be, and checked against
    // the sidecar and the flags as a WKT is; a realization and epoch they
    // cannot state are asked for as for a WKT without them (issue 40
    // point 12). Keys geoanchor does not read (user-defined parameters or
    // codes) refuse the tile unless a sidecar or --crs states its CRS:
    // then they are set aside, with a warning, and whatever the keys do
    // state is still checked against it (a contradiction is refused).
    std::optional<io::LasGeoKeys> keys;
    try {
      keys = io::las_geotiff_crs(reader.vlrs(), tile);
    } catch (const Error& e) {
      if (e.code() != "E_GEOTIFF_KEYS_UNREAD" || !(side || o_.crs)) throw;
      keys = io::las_geotiff_crs(reader.vlrs(), tile, true);
      for (const auto& why : keys->set_aside) {
        p.warnings.push_back(tile + ": GeoTIFF CRS keys: " + why + "; set aside: the tile's CRS is the " +
                             (side ? "sidecar's (" + side_path.string() + ")" : std::string("--crs flag's")) +
                             (keys->crs.empty() ? "" : ", checked against the keys' " + keys->crs));
      }
    }
    if (keys && !keys->crs.empty()) {
      const std::string keys_wkt = io::Crs::parse(keys->crs, tile + " GeoTIFF keys (" + keys->description + ")").wkt2();
      const bool as_crs = side ? side->crs.has_value() : (o_.crs || o_.to_crs);
      wkt = as_crs ? io::tile_metadata_from_wkt_as_crs(keys_wkt, tile) : io::tile_metadata_from_wkt(keys_wkt, tile);
      geotiff_keys = keys->crs + " (" + keys->description + ")";
    }
  }
}

TileMetadata TilePlanner::metadata_from_flags(TilePlan& p, const std::string& tile, const fs::path& side_path) const {
  // Flags only.
  TileMetadata m;
  p.in_frame_source = "command line";
  if (!from_frame_) {
    throw Error(ErrorKind::input, "E_FRAME_UNKNOWN",
                tile + ": the tile's frame is unknown: no sidecar " + side_path.filename().string() +
                    (io::is_las_family(p.format) ? ", no WKT or GeoTIFF keys in the LAS file" : "") +
                    " and no --from-frame NAME@EPOCH");
  }
  m.frame = from_frame_;
  // The frame's own ellipsoid (GRS80 for ITRF, ETRF, GDA, NAD83); --ellipsoid
  // or WGS84 only for a frame that implies none.
  m.coordinates.ellipsoid =
      geodesy::implied_ellipsoid(*from_frame_).value_or(out_.ellipsoid.value_or(geodesy::Ellipsoid::wgs84()));
  if (o_.from_origin) {
    m.coordinates.kind = CoordinateKind::enu;
    m.coordinates.origin = parse_origin(*o_.from_origin, "--from-origin", m.coordinates.ellipsoid);
    m.origin_source = "--from-origin";
  } else if (o_.from_zone) {
    m.coordinates.kind = CoordinateKind::projected;
    m.coordinates.projection = geodesy::utm_projection(m.coordinates.ellipsoid, parse_zone(*o_.from_zone, "--from-zone"));
  } else if (o_.from_tm) {
    m.coordinates.kind = CoordinateKind::projected;
    m.coordinates.projection = geodesy::ProjectionDef{m.coordinates.ellipsoid, parse_tm(*o_.from_tm, "--from-tm"), std::nullopt};
  } else {
    m.coordinates.kind = CoordinateKind::ecef;
  }
  if (p.format == io::TileFormat::csv) {
    // The header names the kind; flags must agree with it.
    const auto cols = io::classify_coordinate_header(p.csv_header, tile);
    if (cols.kind == CoordinateKind::geodetic) {
      if (o_.from_origin || o_.from_zone || o_.from_tm) {
        throw Error(ErrorKind::usage, "E_FRAME_CONFLICT", tile + ": the header has geodetic columns but a --from-origin/"
                                                                 "--from-zone/--from-tm flag was given");
      }
      m.coordinates.kind = CoordinateKind::geodetic;
    } else if (cols.kind == CoordinateKind::ned && m.coordinates.kind == CoordinateKind::enu) {
      m.coordinates.kind = CoordinateKind::ned;
    }
  }
  if (m.coordinates.kind == CoordinateKind::geodetic || m.coordinates.kind == CoordinateKind::projected) {
    m.height_type = "ellipsoidal";  // h_m is ellipsoidal by geoanchor's column convention
  }
  m.storage = io::is_las_family(p.format) ? "int32_scaled" : "float64";
  return m;
}

void TilePlanner::check_flags_against(TileMetadata& m, TilePlan& p, const std::string& tile) const {
  const std::string& what = p.in_frame_source;
  auto conflict = [&](const std::string& flag, const std::string& value, const std::string& stated) {
    throw Error(ErrorKind::usage, "E_FRAME_CONFLICT",
                tile + ": " + flag + " " + value + " contradicts the " + what + ", which says " + stated +
                    "; drop the flag or fix the metadata (flags are never silently preferred)");
  };
  if (o_.crs) {
    const io::Crs flag = io::Crs::parse(*o_.crs, "--crs");
    if (!m.crs) conflict("--crs", *o_.crs, io::kind_name(m) + " coordinates in " + (m.frame ? m.frame->to_string() : "?"));
    const std::optional<io::Crs> both = reconcile_crs(*m.crs, flag);
    if (!both) conflict("--crs", *o_.crs, m.crs->display_name());
    if (!both->same_as(*m.crs)) {
      // --crs says more than the tile: the heights of a 2-D CRS (the same
      // CRS in 3-D or compound), or a dynamic CRS's coordinate epoch.
      TileMetadata stated = io::tile_metadata_from_crs(*both, tile);
      stated.storage = m.storage;
      stated.survey_method = m.survey_method;
      stated.rtk_fixed_percent = m.rtk_fixed_percent;
      stated.metadata = m.metadata;
      stated.provenance_json = m.provenance_json;
      const bool heights = two_d(*m.crs) && !two_d(*both), epoch = !m.crs->epoch() && both->epoch();
      m = std::move(stated);
      p.in_frame_source += std::string(" (") + (heights ? "heights" : "") + (heights && epoch ? " and " : "") +
                           (epoch ? "coordinate epoch" : "") + " stated by --crs)";
    }
  }
  if (m.crs && from_frame_) conflict("--from-frame", *o_.from_frame, m.crs->display_name() + " (its datum is the frame)");
  if (m.crs && (o_.from_origin || o_.from_zone || o_.from_tm)) {
    conflict(o_.from_origin ? "--from-origin" : o_.from_zone ? "--from-zone" : "--from-tm",
             o_.from_origin ? *o_.from_origin : o_.from_zone ? *o_.from_zone : *o_.from_tm, m.crs->display_name());
  }
  if (from_frame_ && m.frame && !(*from_frame_ == *m.frame)) conflict("--from-frame", *o_.from_frame, m.frame->to_string());
  if (o_.from_origin) {
    const auto o = parse_origin(*o_.from_origin, "--from-origin", m.coordinates.ellipsoid);
    if (!m.coordinates.origin) conflict("--from-origin", *o_.from_origin, io::kind_name(m.coordinates) + " coordinates");
    if (!same_origin(o, *m.coordinates.origin)) {
      const auto& s = m.coordinates.origin->point;
      conflict("--from-origin", *o_.from_origin,
               "origin " + format_shortest(s.lat.deg()) + "," + format_shortest(s.lon.deg()) + "," + format_shortest(s.h.m));
    }
  }
  if (o_.from_zone) {
    const auto z = parse_zone(*o_.from_zone, "--from-zone");
    if (!m.coordinates.projection || !m.coordinates.projection->utm || !(*m.coordinates.projection->utm == z)) {
      conflict("--from-zone", *o_.from_zone,
               m.coordinates.projection && m.coordinates.projection->utm ? "UTM zone " + m.coordinates.projection->utm->to_string()
                                                                         : io::kind_name(m.coordinates) + " coordinates");
    }
  }
  if (o_.from_tm) {
    const geodesy::ProjectionDef d{m.coordinates.ellipsoid, parse_tm(*o_.from_tm, "--from-tm"), std::nullopt};
    if (!m.coordinates.projection || !(m.coordinates.projection->tm.lat0 == d.tm.lat0 &&
                                       m.coordinates.projection->tm.lon0 == d.tm.lon0 &&
                                       m.coordinates.projection->tm.k0 == d.tm.k0 &&
                                       m.coordinates.projection->tm.false_easting_m == d.tm.false_easting_m &&
                                       m.coordinates.projection->tm.false_northing_m == d.tm.false_northing_m)) {
      conflict("--from-tm", *o_.from_tm, "another projection (" + io::kind_name(m.coordinates) + ")");
    }
  }
}

TileMetadata TilePlanner::vector_map_metadata(TilePlan& p) const {
  const std::string tile = p.input.string();
  const auto format = p.format;
  const std::string what = format == io::TileFormat::geojson ? "GeoJSON"
                           : format == io::TileFormat::osm   ? "Lanelet2 OSM"
                                                             : "OpenDRIVE";
  if (o_.from_origin || o_.from_zone || o_.from_tm) {
    throw Error(ErrorKind::usage, "E_OPTION",
                tile + ": " + (o_.from_origin ? "--from-origin" : o_.from_zone ? "--from-zone" : "--from-tm") + ": a " +
                    what + " map's coordinates are stated by its format (" +
                    (format == io::TileFormat::xodr ? "the header's geoReference" : "longitude and latitude") +
                    "); give its frame with --from-frame NAME@EPOCH");
  }
  // --crs naming a catalog frame (ITRF2014@2024.5) names the frame of the
  // map's longitudes and latitudes (or of its geoReference's plane); any
  // other CRS only a GeoJSON map can be in.
  std::optional<Frame> flag_frame = from_frame_;
  std::optional<io::Crs> flag_crs;
  if (o_.crs) {
    io::Crs c = io::Crs::parse(*o_.crs, "--crs");
    if (c.from_frame_name()) {
      flag_frame = Frame::parse(*o_.crs, "--crs");
    } else if (format == io::TileFormat::geojson) {
      flag_crs = std::move(c);
    } else {
      throw Error(ErrorKind::usage, "E_OPTION",
                  tile + ": --crs " + *o_.crs + ": a " + what + " map's coordinates are " +
                      (format == io::TileFormat::xodr ? "in the projection of its geoReference"
                                                      : "longitudes and latitudes") +
                      "; --crs may only name their frame (e.g. --crs ITRF2014@2024.5, as --from-frame)");
    }
  }
  const std::string flag_name = from_frame_ ? "--from-frame" : "--crs";
  const fs::path side_path = io::sidecar_path(p.input);
  std::optional<TileMetadata> side;
  std::error_code ec;
  if (fs::exists(side_path, ec)) side = io::read_tile_metadata(side_path);
  const io::VectorMapStatement st = io::read_vector_map_statement(p.input, format);
  const std::string st_name = tile + " " + st.source;
  if (side && st.metadata) {
    TileMetadata stated = *st.metadata;
    if (!stated.frame && !stated.crs) stated.frame = side->frame;  // a geoReference names no frame
    const std::string diff = io::describe_mismatch(*side, side_path.string(), stated, st_name);
    if (!diff.empty()) {
      throw Error(ErrorKind::input, "E_FRAME_CONFLICT", tile + ": the sidecar and the " + st.source + " disagree: " + diff);
    }
  }
  auto conflict = [&](const std::string& flag, const std::string& value, const std::string& stated, const std::string& where) {
    throw Error(ErrorKind::usage, "E_FRAME_CONFLICT",
                tile + ": " + flag + " " + value + " contradicts the " + where + ", which says " + stated +
                    "; drop the flag or fix the metadata (flags are never silently preferred)");
  };
  TileMetadata m;
  if (side || (st.metadata && (st.metadata->frame || st.metadata->crs))) {
    m = side ? *side : *st.metadata;
    p.in_frame_source = side ? "sidecar " + side_path.string() : st_name;
    if (flag_frame && !(m.frame && *m.frame == *flag_frame)) {
      conflict(flag_name, flag_name == "--crs" ? *o_.crs : *o_.from_frame,
               m.frame ? m.frame->to_string() : io::kind_name(m) + " coordinates", p.in_frame_source);
    }
    if (flag_crs && !(m.crs && m.crs->same_as(*flag_crs))) {
      conflict("--crs", *o_.crs, m.crs ? m.crs->display_name() : io::kind_name(m) + " coordinates", p.in_frame_source);
    }
    return m;
  }
  if (flag_crs) {
    m = io::tile_metadata_from_crs(std::move(*flag_crs), tile);
    m.storage = "float64";
    p.in_frame_source = "--crs";
    return m;
  }
  if (!flag_frame) {
    throw Error(ErrorKind::input, "E_FRAME_UNKNOWN",
                tile + ": the map's frame is unknown: no sidecar " + side_path.filename().string() +
                    (format == io::TileFormat::geojson ? ", no 'geoanchor' member (RFC 7946 positions are WGS 84 and "
                                                         "name no realization or epoch)"
                     : format == io::TileFormat::osm ? " (OSM lat/lon name no realization or epoch)"
                                                     : " (a geoReference names no realization or epoch)") +
                    "; give --from-frame NAME@EPOCH (e.g. WGS84(G2139)@2024.5 or ITRF2014@2024.5)");
  }
  if (st.metadata) {
    m = *st.metadata;  // OpenDRIVE: the geoReference's projection
    const auto implied = geodesy::implied_ellipsoid(*flag_frame);
    if (implied && !(*implied == m.coordinates.ellipsoid)) {
      throw Error(ErrorKind::input, "E_ELLIPSOID",
                  tile + ": the geoReference is on " + m.coordinates.ellipsoid.name() + " but " + flag_name + " " +
                      flag_frame->to_string() + " is on " + implied->name() +
                      ": the map's projection and frame contradict each other; fix the geoReference's +ellps (or "
                      "+datum) or give the frame it is on");
    }
  } else {
    m.coordinates.kind = CoordinateKind::geodetic;
    // The frame's own ellipsoid, else the one --ellipsoid names: never a
    // default, which would put the map's latitudes on another ellipsoid.
    const std::optional<geodesy::Ellipsoid> on = geodesy::implied_ellipsoid(*flag_frame);
    if (!on && !out_.ellipsoid) {
      throw Error(ErrorKind::usage, "E_ELLIPSOID",
                  p.input.string() + ": " + flag_name + " " + flag_frame->to_string() +
                      ": geoanchor knows no ellipsoid of this frame, and the map's latitudes and longitudes are on one; "
                      "give it with --ellipsoid");
    }
    m.coordinates.ellipsoid = on ? *on : *out_.ellipsoid;
    m.height_type = "ellipsoidal";
    m.vertical_datum = "ellipsoid " + m.coordinates.ellipsoid.name();
    m.storage = "float64";
  }
  m.frame = flag_frame;
  p.in_frame_source = flag_name + (st.metadata ? " (the frame of the " + st.source + ")" : std::string());
  return m;
}

void TilePlanner::check_vector_output(const TilePlan& p) const {
  const std::string tile = p.input.string();
  const auto kind = p.out.coordinates.kind;
  switch (p.format) {
    case io::TileFormat::geojson:
      if (!p.out.crs && kind != CoordinateKind::geodetic) {
        throw Error(ErrorKind::usage, "E_OPTION",
                    tile + ": a GeoJSON map's positions are longitude, latitude and height (RFC 7946); give --to "
                           "geodetic (or nothing), or --to-crs CRS for another CRS named in a legacy crs member");
      }
      return;
    case io::TileFormat::osm:
      if (p.out.crs || p.in.crs || kind != CoordinateKind::geodetic) {
        throw Error(ErrorKind::usage, "E_OPTION",
                    tile + ": a Lanelet2 OSM map's nodes have lat/lon (geodetic) coordinates; give --to geodetic (or "
                           "nothing), without --to-crs");
      }
      return;
    case io::TileFormat::xodr:
      if (p.out.crs || kind != CoordinateKind::projected || !p.out.coordinates.projection) {
        throw Error(ErrorKind::usage, "E_OPTION",
                    tile + ": an OpenDRIVE map is re-anchored in a Transverse Mercator geoReference; give --to tm "
                           "--tm ..., --to utm --zone Z, or nothing (the map's own projection), without --to-crs");
      }
      return;
    default: return;
  }
}

}  // namespace geoanchor::workflow
