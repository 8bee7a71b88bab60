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

namespace geoanchor::workflow {
namespace {

namespace fs = std::filesystem;
using geodesy::DecimalYear;
using geodesy::Frame;
using io::ArrayFrame;
using io::CoordinateKind;
using io::TileMetadata;

// Origins given twice (flag and sidecar) agree when they name the same
// point to well below a millimetre.
constexpr double kSameOriginDeg = 1e-10;  // ≈ 0.01 mm
constexpr double kSameOriginM = 1e-5;

Frame with_epoch(const Frame& f, DecimalYear e) {
  return Frame::parse(f.name() + "@" + geodesy::format_decimal_year(e), "frame");
}

bool two_d(const io::Crs& c) { return c.description().axes.size() < 3; }

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

io::TileFormat planned_output_format(const ApplyRequest& o, const fs::path& input) {
  const auto in = io::tile_format_of(input);
  if (!in) throw Error(ErrorKind::usage, "E_INPUT", input.string() + ": not a tile");
  if (!o.format) return *in;
  const std::string& f = *o.format;
  if (f != "las" && f != "laz") {
    throw Error(ErrorKind::usage, "E_OPTION", "--format " + f + ": expected las or laz (the output format of LAS and LAZ tiles)");
  }
  if (!io::is_las_family(*in)) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--format " + f + ": " + input.string() + " is a " + std::string(io::to_string(*in)) +
                    " tile, which is written as " + std::string(io::to_string(*in)) +
                    "; --format chooses between LAS and LAZ for LAS and LAZ tiles (leave the others out with "
                    "--exclude GLOB, or run them separately)");
  }
  return f == "laz" ? io::TileFormat::laz : io::TileFormat::las;
}

fs::path planned_output_path(const ApplyRequest& o, const fs::path& input) {
  return fs::path(o.out_dir) / io::tile_output_name(input, planned_output_format(o, input));
}

TilePlanner::TilePlanner(const ApplyRequest& o, const std::optional<io::TransformFile>& t) : o_(o), t_(t) {
  if (o.format && *o.format != "las" && *o.format != "laz") {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--format " + *o.format + ": expected las or laz (the output format of LAS and LAZ tiles)");
  }
  if (o.to) {
    const std::string& k = *o.to;
    if (k == "ecef") {
      out_.kind = CoordinateKind::ecef;
    } else if (k == "geodetic") {
      out_.kind = CoordinateKind::geodetic;
    } else if (k == "enu") {
      out_.kind = CoordinateKind::enu;
    } else if (k == "utm" || k == "tm") {
      out_.kind = CoordinateKind::projected;
      out_.utm = k == "utm";
    } else {
      throw Error(ErrorKind::usage, "E_OPTION", "--to " + k + ": expected ecef, geodetic, enu, utm or tm");
    }
  }
  if (o.zone && o.tm) throw Error(ErrorKind::usage, "E_OPTION", "--zone and --tm: give one");
  if (o.from_zone && o.from_tm) throw Error(ErrorKind::usage, "E_OPTION", "--from-zone and --from-tm: give one");
  if (o.from_origin && (o.from_zone || o.from_tm)) {
    throw Error(ErrorKind::usage, "E_OPTION", "--from-origin with --from-zone/--from-tm: a tile is ENU or projected");
  }
  if (out_.kind == CoordinateKind::projected && out_.utm && o.tm) {
    throw Error(ErrorKind::usage, "E_OPTION", "--to utm with --tm: use --to tm");
  }
  if (out_.kind == CoordinateKind::projected && !out_.utm && o.zone) {
    throw Error(ErrorKind::usage, "E_OPTION", "--to tm with --zone: use --to utm");
  }
  if (o.ellipsoid) out_.ellipsoid = parse_ellipsoid(*o.ellipsoid, "--ellipsoid");
  if (o.from_frame) {
    from_frame_ = Frame::parse(*o.from_frame, "--from-frame");
    // Coordinates in a dynamic frame need their epoch: the frame's, or each
    // LAS point's GPS time.
    if (!o.epoch_from_gps_time) {
      geodesy::require_epoch_if_dynamic(*from_frame_, "--from-frame", ErrorKind::usage,
                                        ", or --epoch-from-gps-time for LAS tiles");
    }
  }
  if (o.inverse && !t) throw Error(ErrorKind::usage, "E_OPTION", "--inverse: needs --transform T.json");
  if (o.to_crs && (o.to || o.origin || o.zone || o.tm || o.ellipsoid)) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--to-crs with --to/--origin/--zone/--tm/--ellipsoid: the CRS states the output's coordinates; give one");
  }
  if (o.crs && (o.from_frame || o.from_origin || o.from_zone || o.from_tm)) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--crs with --from-frame/--from-origin/--from-zone/--from-tm: the CRS states the tile's coordinates; "
                "give one");
  }
  if (o.allow_fallback && !o.crs && !o.to_crs) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--allow-fallback: only with --crs or --to-crs, where PROJ's operation between two datums may need a "
                "grid");
  }
  if (o.epoch_from_gps_time && !(t && t->time_dependent())) {
    throw Error(ErrorKind::usage, "E_OPTION",
                "--epoch-from-gps-time: each LAS point's epoch is what a 14-parameter (time-dependent) --transform is "
                "evaluated at; " + std::string(t ? "this transform does not depend on time" : "there is no --transform") +
                    ", so the epochs would not be used (PROJ's operations between two CRSs take the CRSs' epoch)");
  }
  // Parsed here so that a bad one fails before any tile; each tile parses
  // its own copy (a Crs is one thread's).
  if (o.crs) (void)io::Crs::parse(*o.crs, "--crs");
  if (o.to_crs) (void)io::Crs::parse(*o.to_crs, "--to-crs");
  // Parse the value flags once, so that a bad one fails before any tile.
  const auto e = out_.ellipsoid.value_or(geodesy::Ellipsoid::wgs84());
  if (o.origin) parse_origin(*o.origin, "--origin", e);
  if (o.from_origin) parse_origin(*o.from_origin, "--from-origin", e);
  if (o.zone) parse_zone(*o.zone, "--zone");
  if (o.from_zone) parse_zone(*o.from_zone, "--from-zone");
  if (o.tm) parse_tm(*o.tm, "--tm");
  if (o.from_tm) parse_tm(*o.from_tm, "--from-tm");
  if (o.local_xy) (void)io::parse_local_xy(*o.local_xy, "--local-xy");
}


// What the flags say about a tile with no sidecar and no WKT.
TileMetadata TilePlanner::input_metadata(TilePlan& p) const {
  if (io::is_vector_map(p.format)) return vector_map_metadata(p);
  const std::string tile = p.input.string();
  std::optional<TileMetadata> side, wkt;
  const fs::path side_path = io::sidecar_path(p.input);
  std::error_code ec;
  if (fs::exists(side_path, ec)) side = io::read_tile_metadata(side_path);
  std::optional<std::string> geotiff_keys;
  if (io::is_las_family(p.format)) {
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

TilePlan TilePlanner::plan(const fs::path& input) const {
  TilePlan p = plan_coordinates(input);
  if (io::is_vector_map(p.format)) check_vector_output(p);
  // A tile on the WGS 84 ensemble is known to 2 m at best, as fit warns (issue 40 point 9).
  std::optional<std::string> warned;
  for (const auto* f : {&p.in.frame, &p.out.frame}) {
    if (!*f || (warned && *warned == (*f)->to_string())) continue;
    if (auto w = geodesy::ensemble_warning(**f)) {
      p.warnings.push_back(input.string() + ": " + *w);
      warned = (*f)->to_string();
    }
  }
  return p;
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

TilePlan TilePlanner::plan_coordinates(const fs::path& input) const {
  TilePlan p;
  p.input = input;
  p.format = *io::tile_format_of(input);
  p.output_format = planned_output_format(o_, input);
  p.output = planned_output_path(o_, input);
  p.sidecar = io::sidecar_path(p.output);
  p.in = input_metadata(p);
  const std::string tile = input.string();
  if (p.format == io::TileFormat::csv && p.in.crs && two_d(*p.in.crs)) {
    // A CSV's height column says what its heights are (h_<u> ellipsoidal,
    // H_<u> orthometric): the CRS as its columns read it.
    const io::CrsColumns columns = io::crs_input_columns(*p.in.crs, p.csv_header, tile, p.in_frame_source);
    if (columns.has_height()) {
      const std::string storage = p.in.storage;
      p.in = io::tile_metadata_from_crs(columns.crs, tile);
      p.in.storage = storage;
    }
  }
  // A CSV's '# frame = …' comment (as adjust and convert write it) must say
  // what the sidecar or the flags say; the output does not copy it (its
  // sidecar states the output's frame).
  for (const auto& c : p.csv_comments) {
    const auto v = io::comment_value(c, "frame");
    if (!v) continue;
    const Frame stated = Frame::parse(*v, tile + ": comment '" + c + "'");
    if (!p.in.frame) {
      // A CRS whose datum is no frame of the catalog (an ensemble such as
      // ETRS89, a national datum): the two cannot be compared, as in
      // convert --crs; said, and the comment dropped.
      p.warnings.push_back(tile + ": its '# frame = " + stated.to_string() + "' comment is not copied and was not compared with "
                           "the tile's coordinate system (" + p.in_frame_source + "), which names no frame of geoanchor's catalog");
      continue;
    }
    if (stated.name() != p.in.frame->name() ||
        (stated.epoch() && p.in.frame->epoch() && stated.epoch()->year != p.in.frame->epoch()->year)) {
      throw Error(ErrorKind::input, "E_FRAME_CONFLICT",
                  tile + ": its '# frame = " + stated.to_string() + "' comment contradicts the tile's frame " +
                      p.in.frame->to_string() + " (" + p.in_frame_source + ")");
    }
  }
  const TileMetadata& in = p.in;
  if (in.crs && !in.frame && (t_ || (!o_.to_crs && out_.kind))) {
    throw Error(ErrorKind::input, "E_FRAME_UNKNOWN",
                tile + ": the tile's CRS " + in.crs->display_name() + " (" + p.in_frame_source + ") is on datum '" +
                    in.crs->description().datum + "', which is no frame of geoanchor's catalog" +
                    (t_ ? ", so the transform's source frame cannot be checked against it"
                        : ", so geoanchor's own coordinates cannot be given in it; give --to-crs"));
  }
  if (!in.frame && !in.crs) throw Error(ErrorKind::input, "E_FRAME_UNKNOWN", tile + ": the " + p.in_frame_source + " names no frame");
  // A tile in a dynamic frame without its coordinate epoch: its coordinates
  // are ambiguous by centimetres a year, whatever the transform (the
  // sidecar's "frame", or the LAS WKT's datum), unless each LAS point's GPS
  // time gives its epoch.
  // (A tile in a CRS moved by PROJ alone: PROJ's operation says whether it
  // needs the epoch.)
  if (!(o_.epoch_from_gps_time && io::is_las_family(p.format)) && in.frame && (!in.crs || t_)) {
    geodesy::require_epoch_if_dynamic(*in.frame, tile + ": " + p.in_frame_source + (p.in_frame_source.rfind("sidecar", 0) == 0 ? ": frame" : ""),
                                      ErrorKind::input,
                                      io::is_las_family(p.format) ? ", or --epoch-from-gps-time" : "");
  }
  if (in.height_type == "orthometric" && !in.crs) {
    throw Error(ErrorKind::input, "E_HEIGHT_TYPE",
                tile + ": heights are orthometric (" + in.geoid_model.value_or("geoid not named") +
                    ", per the " + p.in_frame_source +
                    "); apply moves ellipsoidal heights only: convert them to ellipsoidal heights first");
  }

  // The frames: the tile's against the transform's.
  std::optional<Frame> out_frame = in.frame;
  if (t_) {
    const auto& src = o_.inverse ? t_->target_frame : t_->source_frame;
    const auto& dst = o_.inverse ? t_->source_frame : t_->target_frame;
    const char* src_key = o_.inverse ? "target_frame" : "source_frame";
    const char* dst_key = o_.inverse ? "source_frame" : "target_frame";
    if (!src || !dst) {
      if (t_->model != io::TransformModel::enu_origin || src || dst) {
        throw Error(ErrorKind::input, "E_TRANSFORM_FRAMES",
                    *o_.transform + ": the transform names no " + (src ? dst_key : src_key) +
                        "; apply must know both frames to check the tile and label the output (refit with "
                        "--source-frame/--target-frame)");
      }
    } else {
      if (src->name() != in.frame->name()) {
        throw Error(ErrorKind::input, "E_FRAME_MISMATCH",
                    tile + ": the tile is in " + in.frame->to_string() + " (" + p.in_frame_source + ") but the transform's " +
                        src_key + " is " + src->to_string() + " (" + *o_.transform + ")");
      }
      if (t_->time_dependent() && o_.epoch_from_gps_time) {
        if (!io::is_las_family(p.format)) {
          throw Error(ErrorKind::usage, "E_OPTION",
                      tile + ": --epoch-from-gps-time reads LAS GPS times; for per-row epochs in a CSV use "
                             "`geoanchor convert` with an epoch column");
        }
        if (in.frame->epoch()) {
          throw Error(ErrorKind::usage, "E_OPTION",
                      tile + ": the " + p.in_frame_source + " states the coordinate epoch " +
                          geodesy::format_decimal_year(*in.frame->epoch()) +
                          " and --epoch-from-gps-time dates each point by its GPS time: give one");
        }
      } else if (t_->time_dependent()) {
        if (!in.frame->epoch()) {
          throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                      tile + ": the tile's frame " + in.frame->to_string() + " has no coordinate epoch, and the " +
                          "14-parameter transform must be evaluated at it; the reference epoch is never substituted");
        }
        p.epoch = *in.frame->epoch();
      } else if (src->epoch() && !(in.frame->epoch() && *in.frame->epoch() == *src->epoch())) {
        throw Error(ErrorKind::input, "E_FRAME_MISMATCH",
                    tile + ": the tile is in " + in.frame->to_string() + " (" + p.in_frame_source +
                        ") but the transform's " + src_key + " is " + src->to_string() +
                        ": the coordinate epochs differ, and a static transform does not move points in time; "
                        "bring the tile to epoch " + geodesy::format_decimal_year(*src->epoch()) + " first");
      }
      out_frame = dst;
      const bool per_point = t_->time_dependent() && o_.epoch_from_gps_time;
      if (!dst->epoch() && in.frame->epoch() && !per_point) out_frame = with_epoch(*dst, *in.frame->epoch());
    }
  }

  // The output coordinates: flags, else the tile's own.
  TileMetadata& out = p.out;
  out.frame = out_frame;
  out.survey_method = in.survey_method;
  out.rtk_fixed_percent = in.rtk_fixed_percent;
  out.storage = io::is_las_family(p.format) ? "int32_scaled" : "float64";
  if (o_.to_crs || (in.crs && !out_.kind)) {
    plan_crs_stages(p);
    return p;
  }
  if (in.crs) {
    // Into geoanchor's own coordinates: PROJ converts the CRS to its
    // datum's geocentric CRS, geoanchor's chain goes on from there.
    if (two_d(*in.crs)) {
      throw Error(ErrorKind::input, "E_HEIGHT_TYPE",
                  tile + ": the tile's CRS " + in.crs->display_name() + " (" + p.in_frame_source +
                      ") is 2-D: its Z values are no heights PROJ can place; give --crs with the same CRS in 3-D or "
                      "compound (its heights), or a 2-D --to-crs (Z then passes unchanged)");
    }
    p.before = std::make_pair(*in.crs, in.crs->geocentric(tile));
    const geodesy::Ellipsoid e = io::typed_ellipsoid(in.crs->description().ellipsoid);
    p.in.coordinates = ArrayFrame{};
    p.in.coordinates.ellipsoid = e;
  }
  out.coordinates.kind = out_.kind.value_or(in.coordinates.kind);
  // A new frame's ellipsoid (GRS80 for ITRF, ETRF, GDA, NAD83), else the
  // tile's own; --ellipsoid must not contradict the frame for coordinates
  // that use it.
  const bool same_frame = out.frame && in.frame && out.frame->name() == in.frame->name();
  const auto implied = out.frame ? geodesy::implied_ellipsoid(*out.frame) : std::nullopt;
  if (out_.ellipsoid && implied && !(*implied == *out_.ellipsoid) && out.coordinates.kind != CoordinateKind::ecef) {
    throw Error(ErrorKind::usage, "E_ELLIPSOID",
                tile + ": --ellipsoid " + out_.ellipsoid->name() + " contradicts the output frame " + out.frame->to_string() +
                    ", which is on " + implied->name() + "; drop --ellipsoid (the frame says it)");
  }
  out.coordinates.ellipsoid =
      out_.ellipsoid.value_or(implied && !same_frame ? *implied : in.coordinates.ellipsoid);
  const bool same_kind = out.coordinates.kind == in.coordinates.kind;
  if (out.coordinates.kind == CoordinateKind::enu || out.coordinates.kind == CoordinateKind::ned) {
    if (o_.origin) {
      out.coordinates.origin = parse_origin(*o_.origin, "--origin", out.coordinates.ellipsoid);
      out.origin_source = "--origin";
    } else if (in.coordinates.origin) {
      out.coordinates.origin = in.coordinates.origin;
      out.coordinates.origin->ellipsoid = out.coordinates.ellipsoid;
      out.origin_source = in.origin_source;
    } else {
      throw Error(ErrorKind::usage, "E_ORIGIN_MISSING", tile + ": ENU output needs --origin LAT,LON,H");
    }
  } else if (out.coordinates.kind == CoordinateKind::projected) {
    const bool want_utm = out_.kind ? out_.utm : (in.coordinates.projection && in.coordinates.projection->utm);
    if (want_utm && o_.zone) {
      out.coordinates.projection = geodesy::utm_projection(out.coordinates.ellipsoid, parse_zone(*o_.zone, "--zone"));
    } else if (!want_utm && o_.tm) {
      out.coordinates.projection = geodesy::ProjectionDef{out.coordinates.ellipsoid, parse_tm(*o_.tm, "--tm"), std::nullopt};
    } else if (same_kind && in.coordinates.projection && (in.coordinates.projection->utm.has_value() == want_utm)) {
      out.coordinates.projection = in.coordinates.projection;
      out.coordinates.projection->ellipsoid = out.coordinates.ellipsoid;
    } else {
      throw Error(ErrorKind::usage, "E_PROJECTION_MISSING",
                  tile + (want_utm ? ": UTM output needs --zone Z (a tile has one zone)" : ": TM output needs --tm LAT0,LON0,K0,FE,FN"));
    }
  }
  if (io::is_las_family(p.format) &&
      (out.coordinates.kind == CoordinateKind::ned || in.coordinates.kind == CoordinateKind::ned)) {
    throw Error(ErrorKind::usage, "E_TILE_KIND", tile + ": LAS tiles are ENU, not NED");
  }
  // ENU/NED heights are along the ellipsoid normal at an origin given by
  // its ellipsoidal height; only ECEF has no height at all.
  out.height_type = out.coordinates.kind == CoordinateKind::ecef ? "" : "ellipsoidal";
  out.vertical_datum = out.height_type.empty() ? "" : "ellipsoid " + out.coordinates.ellipsoid.name();
  return p;
}

void TilePlanner::plan_crs_stages(TilePlan& p) const {
  const std::string tile = p.input.string();
  TileMetadata& in = p.in;
  TileMetadata& out = p.out;
  if (!o_.to_crs && (o_.origin || o_.zone || o_.tm || o_.ellipsoid)) {
    // The output stays in the tile's CRS, which these flags cannot change.
    throw Error(ErrorKind::usage, "E_OPTION",
                tile + ": the tile is in the CRS " + in.crs->display_name() + " (" + p.in_frame_source + "), so " +
                    (o_.origin ? "--origin" : o_.zone ? "--zone" : o_.tm ? "--tm" : "--ellipsoid") +
                    " says nothing about its output; give --to KIND (geoanchor's own coordinates) or --to-crs CRS");
  }
  io::Crs dst = o_.to_crs ? io::Crs::parse(*o_.to_crs, "--to-crs") : *in.crs;
  const std::string dst_flag = o_.to_crs ? "--to-crs " + *o_.to_crs : "the tile's CRS";
  // The file's heights: a 2-D input has none (Z passes unchanged, to a 2-D
  // output only); a 3-D input keeps them (a 2-D output CRS gets its
  // ellipsoidal height axis, as convert does).
  const bool in_2d = in.crs && two_d(*in.crs);
  if (in_2d && (!two_d(dst) || t_)) {
    throw Error(ErrorKind::input, "E_HEIGHT_TYPE",
                tile + ": the tile's CRS " + in.crs->display_name() + " (" + p.in_frame_source +
                    ") is 2-D: its Z values are no heights PROJ can place; give --crs with the same CRS in 3-D or "
                    "compound (its heights), or a 2-D --to-crs without a transform (Z then passes unchanged)");
  }
  if (!in_2d && two_d(dst)) dst = dst.promoted_to_3d(dst_flag);
  if (in_2d) {
    // Z passes unchanged, so it must mean the same number on both sides: a
    // 2-D CRS states no unit for it (by custom a LAS tile's Z is in the
    // horizontal unit of a projected CRS and in metres beside degrees, but
    // nothing in the file says so), and a change of that unit would leave
    // feet in a tile in metres (issue 40 point 2).
    const auto z_unit = [](const io::Crs& c) -> std::pair<std::string, double> {
      const auto& d = c.description();
      const auto& axes = d.visualization_axes.empty() ? d.axes : d.visualization_axes;
      if (!axes.empty() && axes[0].unit_type == "linear") return {axes[0].unit_name, axes[0].unit_to_si};
      return {"metre", 1.0};
    };
    const auto [ui, si_in] = z_unit(*in.crs);
    const auto [uo, si_out] = z_unit(dst);
    if (si_in != si_out) {
      throw Error(ErrorKind::input, "E_HEIGHT_UNIT",
                  tile + ": the tile's CRS " + in.crs->display_name() + " (" + p.in_frame_source + ") is 2-D in " + ui +
                      " and " + dst_flag + " is 2-D in " + uo + ": the tile's Z values would pass unchanged from " +
                      ui + " into a file in " + uo + ", and no CRS states their unit; give --crs with the tile's CRS in 3-D or "
                      "compound (EPSG:h+v, its heights and their unit), so the heights are converted");
    }
    p.warnings.push_back(tile + ": the tile's CRS " + in.crs->display_name() +
                         " is 2-D: its Z values are no coordinate of it and were copied unchanged into the 2-D output");
  }
  if (!t_) {
    // A dynamic output CRS without its epoch is at the tile's: an operation
    // between realizations is evaluated at one epoch and keeps it.
    const auto in_epoch = in.crs ? in.crs->epoch() : in.frame->epoch();
    if (dst.description().dynamic && !dst.epoch() && in_epoch) dst = dst.at_epoch(*in_epoch, dst_flag);
    if (in.crs && io::is_las_family(p.format) && !o_.resolution_m && in.crs->same_as(dst)) {
      // The tile's own CRS: nothing moves, and the LAS integers, scale and
      // offset are kept (a LAS <-> LAZ conversion keeps every record).
      p.chain_used = false;
      p.keep_coordinates = true;
    } else if (in.crs) {
      p.before = std::make_pair(*in.crs, dst);  // PROJ's own operation between the two
      p.chain_used = false;
    } else {
      // geoanchor's coordinates to their frame's geocentric CRS, then PROJ.
      // A static frame's epoch records when its points were observed (as
      // geoanchor's outputs state ETRF2000@2024.5): no coordinate of its CRS.
      const io::Crs frame = io::Crs::parse(geodesy::is_dynamic(*in.frame) ? in.frame->to_string() : in.frame->name(),
                                           tile + ": the tile's frame");
      p.after = std::make_pair(frame.geocentric(tile), dst);
    }
  } else {
    if (in.crs) {
      p.before = std::make_pair(*in.crs, in.crs->geocentric(tile));
      in.coordinates = ArrayFrame{};
    }
    if (!o_.to_crs) {
      throw Error(ErrorKind::usage, "E_OPTION",
                  tile + ": the tile is in " + in.crs->display_name() + " and the transform moves it into " +
                      out.frame->to_string() + ": give the output's CRS (--to-crs) or kind (--to)");
    }
    const auto& d = dst.description();
    if (d.catalog_frame != out.frame->name()) {
      throw Error(ErrorKind::input, "E_FRAME_MISMATCH",
                  tile + ": " + dst_flag + " is on datum '" + d.datum + "'" +
                      (d.catalog_frame.empty() ? "" : " (" + d.catalog_frame + ")") + " but the transform's output is in " +
                      out.frame->to_string() + ": give a CRS on that frame (e.g. " + out.frame->name() +
                      "), or move the output on with a second apply");
    }
    if (d.dynamic) {
      const auto& fe = out.frame->epoch();
      if (dst.epoch() && fe && dst.epoch()->year != fe->year) {
        throw Error(ErrorKind::input, "E_CRS_EPOCH",
                    tile + ": " + dst_flag + " is at epoch " + geodesy::format_decimal_year(*dst.epoch()) +
                        " but the transform's output is at " + geodesy::format_decimal_year(*fe) +
                        ": a transform does not move points in time");
      }
      // Per-point epochs (--epoch-from-gps-time) leave the output without
      // one epoch: the conversion to the CRS needs none.
      const bool per_point = o_.epoch_from_gps_time && io::is_las_family(p.format);
      if (per_point && dst.epoch()) {
        throw Error(ErrorKind::usage, "E_OPTION",
                    tile + ": " + dst_flag + " names the epoch " + geodesy::format_decimal_year(*dst.epoch()) +
                        " but --epoch-from-gps-time leaves each point at its own GPS time; give the CRS without it");
      }
      if (!dst.epoch() && !fe && !per_point) {
        throw Error(ErrorKind::input, "E_EPOCH_MISSING",
                    tile + ": " + dst_flag + " is dynamic and the transform's output has no coordinate epoch; give "
                                             "--to-crs CRS@EPOCH");
      }
      if (!dst.epoch() && fe) dst = dst.at_epoch(*fe, dst_flag);
    }
    p.after = std::make_pair(dst.geocentric(dst_flag), dst);
  }
  // The output in the CRS (its coordinates ECEF between the stages), with
  // the tile's survey record; a static frame keeps the epoch of its
  // coordinates' observation, as geoanchor's own outputs record it
  // (ETRF2000@2024.5).
  io::TileMetadata in_crs = io::tile_metadata_from_crs(dst, tile);
  if (out.frame && in_crs.frame && !in_crs.frame->epoch()) {
    // A static output frame (ETRF2000, GDA2020) is labelled with the
    // epoch its points were observed at, as the input states it.
    if (out.frame->name() == in_crs.frame->name()) {
      in_crs.frame = out.frame;
    } else if (out.frame->epoch()) {
      in_crs.frame = with_epoch(*in_crs.frame, *out.frame->epoch());
    }
  }
  in_crs.storage = out.storage;
  in_crs.survey_method = out.survey_method;
  in_crs.rtk_fixed_percent = out.rtk_fixed_percent;
  out = std::move(in_crs);
}

}  // namespace geoanchor::workflow
