// LAS tiles through a PointChain: X, Y, Z decoded to float64, transformed,
// and re-quantized at the output's scale and offset; every other byte of
// every record passes through.

#include <chrono>
#include <cstring>
#include <ctime>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/number_text.hpp"
#include "geoanchor/io/las.hpp"
#include "tile_common.hpp"

namespace geoanchor::io {
namespace {

using detail::Bounds;

// Metres per degree of latitude (mean, to 1 %): only used to turn a
// quantization step in metres into one in degrees and back.
constexpr double kMetresPerDegree = 111319.49;
constexpr double kInt32Max = 2147483647.0;
constexpr double kInt32Min = -2147483648.0;

double pow10_floor(double v) { return std::pow(10.0, std::floor(std::log10(v))); }

// The resolution in metres of the input's horizontal and vertical axes.
std::array<double, 2> input_resolution_m(const LasHeader& h, const ArrayFrame& from) {
  if (from.kind == CoordinateKind::geodetic) {
    const double lat = 0.5 * (h.min[1] + h.max[1]);
    const double coslat = std::isfinite(lat) && std::abs(lat) <= 90.0 ? std::cos(lat * M_PI / 180.0) : 1.0;
    const double lon_m = h.scale[0] * kMetresPerDegree * std::max(coslat, 1e-3);
    return {std::min(lon_m, h.scale[1] * kMetresPerDegree), h.scale[2]};
  }
  if (from.kind == CoordinateKind::ecef) {
    const double r = std::min({h.scale[0], h.scale[1], h.scale[2]});
    return {r, r};
  }
  return {std::min(h.scale[0], h.scale[1]), h.scale[2]};
}

std::array<double, 3> output_scale(const std::array<double, 2>& res, const ArrayFrame& to) {
  if (to.kind == CoordinateKind::geodetic) {
    const double deg = pow10_floor(res[0] / kMetresPerDegree);
    return {deg, deg, res[1]};
  }
  if (to.kind == CoordinateKind::ecef) {
    const double r = std::min(res[0], res[1]);
    return {r, r, r};
  }
  return {res[0], res[0], res[1]};
}

// An offset near the middle of [lo, hi], on a grid of 1000 steps.
double centred_offset(double lo, double hi, double scale) {
  const double unit = scale * 1000.0;
  return std::nearbyint(0.5 * (lo + hi) / unit) * unit;
}

struct Overflow {
  std::uint64_t point;
  int axis;
  double value;
};

class LasTile {
 public:
  LasTile(const std::filesystem::path& in, std::ostream& out, std::string out_name, const PointChain& chain,
          const TileApplyOptions& o)
      : reader_(in), out_(out), out_name_(std::move(out_name)), chain_(chain), o_(o) {}

  TileApplyResult run();

 private:
  // Reads every point, transforms it, and hands (X, Y, Z) in file axes to
  // `sink` chunk by chunk; the records are in `buffer_`.
  template <class Sink>
  void pass(Sink&& sink);
  void write_pass(LasWriter& writer, const std::array<double, 3>& scale, const std::array<double, 3>& offset,
                  TileApplyResult& r);

  LasReader reader_;
  std::ostream& out_;
  std::string out_name_;
  const PointChain& chain_;
  const TileApplyOptions& o_;
  std::vector<std::uint8_t> buffer_;
  std::vector<double> x_, y_, z_;
  Bounds in_bounds_;
};

template <class Sink>
void LasTile::pass(Sink&& sink) {
  const LasHeader& h = reader_.header();
  const std::size_t len = h.record_length;
  const bool geo_in = detail::lon_first_in_files(o_.from);
  const bool geo_out = detail::lon_first_in_files(o_.to);
  reader_.rewind();
  std::uint64_t done = 0;
  x_.resize(o_.chunk_points);
  y_.resize(o_.chunk_points);
  z_.resize(o_.chunk_points);
  while (const std::size_t n = reader_.read_records(buffer_, o_.chunk_points)) {
    const std::uint8_t* p = buffer_.data();
    for (std::size_t i = 0; i < n; ++i, p += len) {
      std::int32_t q[3];
      std::memcpy(q, p, sizeof q);
      x_[i] = q[0] * h.scale[0] + h.offset[0];
      y_[i] = q[1] * h.scale[1] + h.offset[1];
      z_[i] = q[2] * h.scale[2] + h.offset[2];
    }
    // Chain order: (lat, lon, h) for geodetic, (X, Y, Z) otherwise.
    std::span<double> a(geo_in ? y_.data() : x_.data(), n);
    std::span<double> b(geo_in ? x_.data() : y_.data(), n);
    std::span<double> c(z_.data(), n);
    in_bounds_.add(a, b, c);
    chain_.apply(a, b, c);
    // The chain wrote the output in its order into the same arrays.
    std::span<double> xs = geo_out ? b : a;
    std::span<double> ys = geo_out ? a : b;
    if (const std::size_t bad = detail::first_non_finite(xs, ys, c); bad < n) {
      throw Error(ErrorKind::input, "E_TRANSFORM",
                  reader_.path().string() + ": point " + std::to_string(done + bad + 1) + " (byte " +
                      std::to_string(h.offset_to_points + (done + bad) * len) +
                      ") has no finite position in the output frame");
    }
    sink(xs, ys, c, n, done);
    done += n;
    if (o_.progress) o_.progress(done);
  }
}

void LasTile::write_pass(LasWriter& writer, const std::array<double, 3>& scale, const std::array<double, 3>& offset,
                         TileApplyResult& r) {
  const std::size_t len = reader_.header().record_length;
  const double inv[3] = {1.0 / scale[0], 1.0 / scale[1], 1.0 / scale[2]};
  std::array<std::int64_t, 3> qmin{INT64_MAX, INT64_MAX, INT64_MAX}, qmax{INT64_MIN, INT64_MIN, INT64_MIN};
  pass([&](std::span<double> xs, std::span<double> ys, std::span<double> zs, std::size_t n, std::uint64_t done) {
    std::uint8_t* p = buffer_.data();
    const std::span<double> axes[3] = {xs, ys, zs};
    for (int k = 0; k < 3; ++k) {
      const auto ku = static_cast<std::size_t>(k);
      const double* v = axes[k].data();
      std::int64_t lo = qmin[ku], hi = qmax[ku];
      bool bad = false;
      for (std::size_t i = 0; i < n; ++i) {
        const double t = (v[i] - offset[ku]) * inv[ku];
        bad |= !(t > kInt32Min - 0.5 && t < kInt32Max + 0.5);
        // Round half away from zero with a plain conversion (lround is an
        // out-of-line call, about 2x slower here).
        // Clamped first only so that the conversion is defined; a value out
        // of range has set `bad` and is never written.
        const double tc = std::clamp(t, 2.0 * kInt32Min, 2.0 * kInt32Max);
        const auto q = static_cast<std::int64_t>(tc + (tc >= 0.0 ? 0.5 : -0.5));
        lo = std::min(lo, q);
        hi = std::max(hi, q);
        const auto q32 = static_cast<std::int32_t>(q);
        std::memcpy(p + i * len + 4 * ku, &q32, 4);
      }
      if (bad) {
        for (std::size_t i = 0; i < n; ++i) {
          const double t = (v[i] - offset[ku]) * inv[ku];
          if (!(t > kInt32Min - 0.5 && t < kInt32Max + 0.5)) throw Overflow{done + i + 1, k, v[i]};
        }
      }
      qmin[ku] = lo;
      qmax[ku] = hi;
    }
    writer.write_records(buffer_.data(), n);
  });
  for (std::size_t k = 0; k < 3; ++k) {
    r.min[k] = r.points ? static_cast<double>(qmin[k]) * scale[k] + offset[k] : 0.0;
    r.max[k] = r.points ? static_cast<double>(qmax[k]) * scale[k] + offset[k] : 0.0;
  }
}

TileApplyResult LasTile::run() {
  const LasHeader& h = reader_.header();
  for (const ArrayFrame* f : {&o_.from, &o_.to}) {
    if (f->kind == CoordinateKind::ned) {
      throw Error(ErrorKind::usage, "E_TILE_KIND", reader_.path().string() + ": LAS tiles are ENU, not NED");
    }
  }
  TileApplyResult r;
  r.points = h.point_count;
  r.storage = "int32_scaled";

  // Scale: the input's resolution (or --resolution), in the output's units.
  std::array<double, 2> res = input_resolution_m(h, o_.from);
  if (o_.resolution_m) res = {*o_.resolution_m, *o_.resolution_m};
  r.scale = output_scale(res, o_.to);

  // Offset: the middle of the header's bounds carried through the chain.
  std::array<double, 3> lo = h.min, hi = h.max;
  std::vector<double> ca, cb, cc;
  for (int corner = 0; corner < 8; ++corner) {
    const double x = corner & 1 ? hi[0] : lo[0];
    const double y = corner & 2 ? hi[1] : lo[1];
    const double z = corner & 4 ? hi[2] : lo[2];
    const bool geo_in = detail::lon_first_in_files(o_.from);
    ca.push_back(geo_in ? y : x);
    cb.push_back(geo_in ? x : y);
    cc.push_back(z);
  }
  chain_.apply(ca, cb, cc);
  const bool geo_out = detail::lon_first_in_files(o_.to);
  Bounds est;
  est.add(geo_out ? cb : ca, geo_out ? ca : cb, cc);
  for (std::size_t k = 0; k < 3; ++k) {
    r.offset[k] = std::isfinite(est.min[k]) && std::isfinite(est.max[k]) ? centred_offset(est.min[k], est.max[k], r.scale[k])
                                                                         : 0.0;
  }

  // VLRs: every one but the old CRS (WKT or GeoTIFF), which the new WKT replaces.
  std::vector<LasVlr> vlrs, evlrs;
  bool dropped_crs = false;
  for (const auto& v : reader_.vlrs()) {
    if (is_wkt_crs_vlr(v) || is_geotiff_crs_vlr(v)) {
      dropped_crs = true;
      continue;
    }
    (v.extended ? evlrs : vlrs).push_back(v);
  }
  if (dropped_crs) r.warnings.push_back(reader_.path().string() + ": the input's CRS records were replaced by the output's WKT");
  LasVlr wkt;
  wkt.user_id = "LASF_Projection";
  wkt.record_id = kLasWktRecordId;
  wkt.description = "OGC WKT2:2019 CRS (geoanchor)";
  wkt.data.assign(o_.output_wkt.begin(), o_.output_wkt.end());
  wkt.data.push_back(0);
  vlrs.insert(vlrs.begin(), std::move(wkt));

  LasHeader oh = h;
  oh.global_encoding = static_cast<std::uint16_t>(oh.global_encoding | LasHeader::kWktBit);
  oh.generating_software.fill(0);
  const std::string software = "geoanchor";
  std::memcpy(oh.generating_software.data(), software.data(), software.size());
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  oh.creation_day = static_cast<std::uint16_t>(utc.tm_yday + 1);
  oh.creation_year = static_cast<std::uint16_t>(utc.tm_year + 1900);
  oh.scale = r.scale;
  oh.offset = r.offset;
  LasWriter writer(out_, oh, std::move(vlrs), std::move(evlrs), out_name_);

  try {
    write_pass(writer, r.scale, r.offset, r);
  } catch (const Overflow&) {
    // The header's bounds were wrong (or the chain bends them): take the
    // true bounds of the output and try once more from the middle of them.
    Bounds exact;
    pass([&](std::span<double> xs, std::span<double> ys, std::span<double> zs, std::size_t, std::uint64_t) {
      exact.add(xs, ys, zs);
    });
    for (std::size_t k = 0; k < 3; ++k) r.offset[k] = centred_offset(exact.min[k], exact.max[k], r.scale[k]);
    writer.restart(r.offset);
    try {
      write_pass(writer, r.scale, r.offset, r);
    } catch (const Overflow& e) {
      const char* axis = e.axis == 0 ? "X" : e.axis == 1 ? "Y" : "Z";
      const auto ku = static_cast<std::size_t>(e.axis);
      throw Error(ErrorKind::input, "E_INT32_OVERFLOW",
                  out_name_ + ": point " + std::to_string(e.point) + ": " + axis + " = " +
                      format_shortest(e.value) + " does not fit a 32-bit integer at scale " +
                      format_shortest(r.scale[ku]) + " and offset " + format_shortest(r.offset[ku]) +
                      " (the tile spans " + format_shortest(exact.max[ku] - exact.min[ku]) +
                      " on this axis); give a coarser --resolution or split the tile. Values are never clamped");
    }
  }
  writer.finish(h.points_by_return, r.min, r.max);
  r.in_min = in_bounds_.min;
  r.in_max = in_bounds_.max;
  return r;
}

}  // namespace

TileApplyResult apply_las_tile(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                               const PointChain& chain, const TileApplyOptions& o) {
  LasTile tile(in, out, out_name, chain, o);
  return tile.run();
}

}  // namespace geoanchor::io
