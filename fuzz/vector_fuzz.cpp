// libFuzzer target: vector maps (GeoJSON, Lanelet2 OSM XML, OpenDRIVE) read
// and moved through an identity chain; the same bytes as each format. The
// statement readers (GeoJSON's members, OpenDRIVE's geoReference) too.

#include <sstream>

#include "fuzz_support.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/io/vector/vector_map.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace geoanchor;
  const io::ArrayFrame geodetic = fuzz::frame(io::CoordinateKind::geodetic);
  io::ArrayFrame tm = fuzz::frame(io::CoordinateKind::projected);
  tm.projection = geodesy::ProjectionDef{
      geodesy::Ellipsoid::grs80(), {geodesy::Angle::degrees(47.45), geodesy::Angle::degrees(8.55), 1.0, 0.0, 0.0}, std::nullopt};
  struct Kind {
    const char* extension;
    io::TileFormat format;
    const io::ArrayFrame& frame;
  };
  for (const Kind& k : {Kind{".geojson", io::TileFormat::geojson, geodetic}, Kind{".osm", io::TileFormat::osm, geodetic},
                        Kind{".xodr", io::TileFormat::xodr, tm}}) {
    const auto path = fuzz::as_file(data, size, k.extension);
    try {
      (void)io::read_vector_map_statement(path, k.format);
    } catch (const Error&) {
    }
    try {
      const io::PointChain chain(k.frame, std::nullopt, false, std::nullopt, k.frame);
      io::TileApplyOptions o{k.frame, k.frame, std::nullopt, "", 8, {}};
      o.local_xy = "lanelet2-utm:47.46,8.55";
      std::stringstream out;
      if (k.format == io::TileFormat::geojson) io::apply_geojson_map(path, out, "out.geojson", chain, o);
      if (k.format == io::TileFormat::osm) io::apply_osm_map(path, out, "out.osm", chain, o);
      if (k.format == io::TileFormat::xodr) io::apply_xodr_map(path, out, "out.xodr", chain, o);
    } catch (const Error&) {
    }
  }
  return 0;
}
