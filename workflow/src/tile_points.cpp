#include "tile_points.hpp"

#include <algorithm>
#include <ios>
#include <ostream>
#include <streambuf>

#include "geoanchor/base/error.hpp"
#include "geoanchor/io/tile/tile_apply.hpp"
#include "geoanchor/io/vector/vector_map.hpp"

namespace geoanchor::workflow::detail {
namespace {

// A seekable output that keeps nothing: the readers write an output as they
// read, and only what they found matters here.
class DiscardBuffer : public std::streambuf {
 protected:
  int_type overflow(int_type c) override {
    if (!traits_type::eq_int_type(c, traits_type::eof())) advance(1);
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char*, std::streamsize n) override {
    advance(n);
    return n;
  }
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override {
    const off_type base = dir == std::ios_base::beg ? 0 : dir == std::ios_base::cur ? at_ : end_;
    if (base + off < 0) return pos_type(off_type(-1));
    at_ = base + off;
    return pos_type(at_);
  }
  pos_type seekpos(pos_type p, std::ios_base::openmode which) override { return seekoff(off_type(p), std::ios_base::beg, which); }

 private:
  void advance(std::streamsize n) {
    at_ += n;
    end_ = std::max(end_, at_);
  }
  off_type at_ = 0, end_ = 0;
};

}  // namespace

std::pair<Eigen::Vector3d, Eigen::Vector3d> point_extent(const std::filesystem::path& file, const io::ArrayFrame& coordinates,
                                                         const std::optional<std::string>& local_xy) {
  const auto format = io::tile_format_of(file);
  if (!format) throw Error(ErrorKind::input, "E_TILE_FORMAT", file.string() + ": not a tile or vector map geoanchor reads");
  const io::PointChain identity(coordinates, std::nullopt, false, std::nullopt, coordinates);
  io::TileApplyOptions o{coordinates, coordinates, std::nullopt, "", 1 << 16, {}};
  o.las_output = io::TileFormat::las;  // nothing to compress
  o.local_xy = local_xy;
  DiscardBuffer discard;
  std::ostream out(&discard);
  const std::string name = file.string();
  io::TileApplyResult r;
  switch (*format) {
    case io::TileFormat::las:
    case io::TileFormat::laz: r = io::apply_las_tile(file, out, name, identity, o); break;
    case io::TileFormat::csv: r = io::apply_csv_tile(file, out, name, identity, o); break;
    case io::TileFormat::ply: r = io::apply_ply_tile(file, out, name, identity, o); break;
    case io::TileFormat::geojson: r = io::apply_geojson_map(file, out, name, identity, o); break;
    case io::TileFormat::osm: r = io::apply_osm_map(file, out, name, identity, o); break;
    case io::TileFormat::xodr: r = io::apply_xodr_map(file, out, name, identity, o); break;
  }
  return {Eigen::Vector3d(r.min[0], r.min[1], r.min[2]), Eigen::Vector3d(r.max[0], r.max[1], r.max[2])};
}

}  // namespace geoanchor::workflow::detail
