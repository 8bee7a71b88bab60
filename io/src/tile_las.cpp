// LAS tiles through a PointChain: X, Y, Z decoded to float64, transformed,
// and re-quantized at the output's scale and offset; every other byte of
// every record passes through.

#include <chrono>
#include <cstring>
#include <ctime>
#include <limits>

#include "geoanchor/geodesy/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
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

// The power of ten at or below v (v itself when it is one: log10 may miss
// an exact power by an ulp).
double pow10_floor(double v) {
  constexpr double kLogSlack = 1e-9;
  return std::pow(10.0, std::floor(std::log10(v) + kLogSlack));
}

// The resolution in metres of the input's horizontal and vertical axes.
std::array<double, 2> input_resolution_m(const LasHeader& h, const ArrayFrame& from, const std::optional<TileCrsAxes>& crs) {
  if (crs && !crs->angular && !crs->geocentric) {
    return {std::min(h.scale[0], h.scale[1]) * crs->horizontal_unit, h.scale[2] * crs->vertical_m};
  }
  if (crs ? crs->angular : from.kind == CoordinateKind::geodetic) {
    const double unit_deg = crs ? crs->horizontal_unit : 1.0;
    const double lat = 0.5 * (h.min[1] + h.max[1]) * unit_deg;
    const double coslat = std::isfinite(lat) && std::abs(lat) <= 90.0 ? std::cos(lat * M_PI / 180.0) : 1.0;
    const double lon_m = h.scale[0] * unit_deg * kMetresPerDegree * std::max(coslat, 1e-3);
    return {std::min(lon_m, h.scale[1] * unit_deg * kMetresPerDegree), h.scale[2] * (crs ? crs->vertical_m : 1.0)};
  }
  if (crs || from.kind == CoordinateKind::ecef) {
    const double r = std::min({h.scale[0], h.scale[1], h.scale[2]});
    return {r, r};
  }
  return {std::min(h.scale[0], h.scale[1]), h.scale[2]};
}

// The output's scale: the resolution in its units, a power of ten at or
// below it where the unit is not the metre.
std::array<double, 3> output_scale(const std::array<double, 2>& res, const ArrayFrame& to, const std::optional<TileCrsAxes>& crs) {
  if (crs && !crs->geocentric) {
    const double z = crs->vertical_m == 1.0 ? res[1] : pow10_floor(res[1] / crs->vertical_m);
    if (crs->angular) {
      const double unit = pow10_floor(res[0] / kMetresPerDegree / crs->horizontal_unit);
      return {unit, unit, z};
    }
    const double xy = crs->horizontal_unit == 1.0 ? res[0] : pow10_floor(res[0] / crs->horizontal_unit);
    return {xy, xy, z};
  }
  if (!crs && to.kind == CoordinateKind::geodetic) {
    const double deg = pow10_floor(res[0] / kMetresPerDegree);
    return {deg, deg, res[1]};
  }
  if (crs || to.kind == CoordinateKind::ecef) {
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
  std::vector<std::int32_t> q_;
  std::vector<double> epochs_;
  std::size_t gps_time_offset_ = 0;
  double epoch_lo_ = std::numeric_limits<double>::infinity(), epoch_hi_ = -std::numeric_limits<double>::infinity();
  std::array<std::int32_t, 3> in_qmin_{INT32_MAX, INT32_MAX, INT32_MAX}, in_qmax_{INT32_MIN, INT32_MIN, INT32_MIN};
  UtmBandTally band_in_, band_out_;  // of the last pass: points outside a UTM zone's band
};

template <class Sink>
void LasTile::pass(Sink&& sink) {
  const LasHeader& h = reader_.header();
  const std::size_t len = h.record_length;
  const bool geo_in = detail::lon_first_in_files(o_.from);
  const bool geo_out = detail::lon_first_in_files(o_.to);
  reader_.rewind();
  band_in_ = band_out_ = UtmBandTally{};
  std::uint64_t done = 0;
  x_.resize(o_.chunk_points);
  y_.resize(o_.chunk_points);
  z_.resize(o_.chunk_points);
  while (const std::size_t n = reader_.read_records(buffer_, o_.chunk_points)) {
    const std::uint8_t* p = buffer_.data();
    double* xs_in = x_.data();
    double* ys_in = y_.data();
    double* zs_in = z_.data();
    const double sx = h.scale[0], sy = h.scale[1], sz = h.scale[2];
    const double ox = h.offset[0], oy = h.offset[1], oz = h.offset[2];
    std::int32_t lo0 = in_qmin_[0], lo1 = in_qmin_[1], lo2 = in_qmin_[2];
    std::int32_t hi0 = in_qmax_[0], hi1 = in_qmax_[1], hi2 = in_qmax_[2];
    for (std::size_t i = 0; i < n; ++i, p += len) {
      std::int32_t q[3];
      std::memcpy(q, p, sizeof q);
      lo0 = std::min(lo0, q[0]), hi0 = std::max(hi0, q[0]);
      lo1 = std::min(lo1, q[1]), hi1 = std::max(hi1, q[1]);
      lo2 = std::min(lo2, q[2]), hi2 = std::max(hi2, q[2]);
      xs_in[i] = q[0] * sx + ox;
      ys_in[i] = q[1] * sy + oy;
      zs_in[i] = q[2] * sz + oz;
    }
    in_qmin_ = {lo0, lo1, lo2};
    in_qmax_ = {hi0, hi1, hi2};
    // Chain order: (lat, lon, h) for geodetic, (X, Y, Z) otherwise.
    std::span<double> a(geo_in ? y_.data() : x_.data(), n);
    std::span<double> b(geo_in ? x_.data() : y_.data(), n);
    std::span<double> c(z_.data(), n);
    auto point_name = [&](std::size_t i) {
      return "point " + std::to_string(done + i + 1) + " (byte " + std::to_string(h.offset_to_points + (done + i) * len) +
             ")";
    };
    if (o_.epochs_from_gps_time) {
      // Adjusted standard GPS time: GPS seconds minus 1e9.
      epochs_.resize(n);
      const std::uint8_t* g = buffer_.data() + gps_time_offset_;
      for (std::size_t i = 0; i < n; ++i, g += len) {
        double adjusted = 0.0;
        std::memcpy(&adjusted, g, sizeof adjusted);
        if (!std::isfinite(adjusted)) {
          throw Error(ErrorKind::input, "E_GPS_TIME",
                      reader_.path().string() + ": point " + std::to_string(done + i + 1) + " (byte " +
                          std::to_string(h.offset_to_points + (done + i) * len) + ") has a non-finite GPS time");
        }
        epochs_[i] = geodesy::decimal_year_from_gps_seconds(adjusted + 1.0e9).year;
        epoch_lo_ = std::min(epoch_lo_, epochs_[i]);
        epoch_hi_ = std::max(epoch_hi_, epochs_[i]);
      }
    }
    const ChainReport report =
        detail::move_points(chain_, o_, a, b, c, o_.epochs_from_gps_time ? &epochs_ : nullptr, point_name);
    // The chain wrote the output in its order into the same arrays.
    std::span<double> xs = geo_out ? b : a;
    std::span<double> ys = geo_out ? a : b;
    if (const std::size_t bad = detail::first_non_finite(xs, ys, c); bad < n) {
      throw Error(ErrorKind::input, "E_TRANSFORM",
                  reader_.path().string() + ": " + point_name(bad) + " has no finite position in the output frame" +
                      detail::refusal_reason(report, bad) + "; nothing was written");
    }
    band_in_.absorb(report.input_band, point_name(report.input_band.worst_index));
    band_out_.absorb(report.output_band, point_name(report.output_band.worst_index));
    sink(xs, ys, c, n, done);
    done += n;
    if (o_.progress) o_.progress(done);
  }
}

// Round-to-nearest by the float64 magic number (exact for |t| < 2^51): a
// branch-free rounding that vectorises, where lround is an out-of-line call.
constexpr double kRoundMagic = 6755399441055744.0;  // 1.5 * 2^52

// q[i] = round((v[i] - off) * inv) as int32, widening [lo, hi]; false when
// a value does not fit int32 (that q[i] is then meaningless). Cloned for
// AVX2, where signed 32-bit min/max vectorise (baseline SSE2 has no pminsd).
__attribute__((target_clones("arch=x86-64-v3", "default")))
bool quantize(const double* v, std::int32_t* q, std::size_t n, double off, double inv, std::int32_t& lo_io,
              std::int32_t& hi_io) {
  std::int32_t lo = lo_io, hi = hi_io;
  int ok = 1;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = (v[i] - off) * inv;
    const int inside = static_cast<int>(t > kInt32Min - 0.5) & static_cast<int>(t < kInt32Max + 0.5);
    ok &= inside;
    // Replaced only so that the conversion is defined; a value out of range
    // has cleared `ok` and is never written. (A select, unlike std::min/max
    // on doubles, lets GCC vectorise the loop.)
    const double tc = inside ? t : 0.0;
    const auto qi = static_cast<std::int32_t>((tc + kRoundMagic) - kRoundMagic);
    q[i] = qi;
    lo = std::min(lo, qi);
    hi = std::max(hi, qi);
  }
  lo_io = lo;
  hi_io = hi;
  return ok != 0;
}

void LasTile::write_pass(LasWriter& writer, const std::array<double, 3>& scale, const std::array<double, 3>& offset,
                         TileApplyResult& r) {
  const std::size_t len = reader_.header().record_length;
  std::array<std::int32_t, 3> qmin{INT32_MAX, INT32_MAX, INT32_MAX}, qmax{INT32_MIN, INT32_MIN, INT32_MIN};
  q_.resize(3 * o_.chunk_points);
  pass([&](std::span<double> xs, std::span<double> ys, std::span<double> zs, std::size_t n, std::uint64_t done) {
    const std::span<double> axes[3] = {xs, ys, zs};
    for (std::size_t k = 0; k < 3; ++k) {
      const double* v = axes[k].data();
      std::int32_t* q = q_.data() + k * o_.chunk_points;
      const double off = offset[k], inv = 1.0 / scale[k];
      const bool ok = quantize(v, q, n, off, inv, qmin[k], qmax[k]);
      if (!ok) {
        for (std::size_t i = 0; i < n; ++i) {
          const double t = (v[i] - off) * inv;
          if (!(t > kInt32Min - 0.5 && t < kInt32Max + 0.5)) throw Overflow{done + i + 1, static_cast<int>(k), v[i]};
        }
      }
    }
    // Scatter X, Y, Z into the records; every other byte stays.
    const std::int32_t* qx = q_.data();
    const std::int32_t* qy = qx + o_.chunk_points;
    const std::int32_t* qz = qy + o_.chunk_points;
    std::uint8_t* p = buffer_.data();
    for (std::size_t i = 0; i < n; ++i, p += len) {
      const std::int32_t xyz[3] = {qx[i], qy[i], qz[i]};
      std::memcpy(p, xyz, sizeof xyz);
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
  if (o_.epochs_from_gps_time) {
    if (h.point_format == 0 || h.point_format == 2) {
      throw Error(ErrorKind::input, "E_GPS_TIME",
                  reader_.path().string() + ": byte 104: point format " + std::to_string(h.point_format) +
                      " has no GPS time, so the points' epochs are unknown");
    }
    if ((h.global_encoding & 1u) == 0) {
      throw Error(ErrorKind::input, "E_GPS_TIME",
                  reader_.path().string() + ": byte 6: the GPS times are GPS week seconds (global encoding bit 0 "
                                            "clear), which do not say the week; per-point epochs need adjusted "
                                            "standard GPS time");
    }
    gps_time_offset_ = h.point_format >= 6 ? 22 : 20;
  }

  // Scale: the input's resolution (or --resolution), in the output's units.
  std::array<double, 2> res = input_resolution_m(h, o_.from, o_.file_in);
  if (o_.resolution_m) res = {*o_.resolution_m, *o_.resolution_m};
  r.scale = output_scale(res, o_.to, o_.file_out);
  // Angles in and out in the same unit: the input's steps stay (a step in
  // metres would shrink by cos(latitude) on each pass).
  const bool angular_in = o_.file_in ? o_.file_in->angular : o_.from.kind == CoordinateKind::geodetic;
  const bool angular_out = o_.file_out ? o_.file_out->angular : o_.to.kind == CoordinateKind::geodetic;
  const double unit_in = o_.file_in ? o_.file_in->horizontal_unit : 1.0;
  const double unit_out = o_.file_out ? o_.file_out->horizontal_unit : 1.0;
  if (!o_.resolution_m && angular_in && angular_out && unit_in == unit_out) {
    r.scale[0] = h.scale[0];
    r.scale[1] = h.scale[1];
  }

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
  // Only an estimate for the offset: any epoch moves the corners by
  // centimetres at most, far inside the int32 range.
  constexpr double kAnyEpoch = 2000.0;
  const std::vector<double> any_epoch(ca.size(), kAnyEpoch);
  detail::estimate_points(chain_, o_, ca, cb, cc, o_.epochs_from_gps_time ? &any_epoch : nullptr);
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
  detail::add_band_warnings(r, reader_.path().string(), band_in_, band_out_);
  if (o_.epochs_from_gps_time && r.points) r.epoch_range = std::array<double, 2>{epoch_lo_, epoch_hi_};
  // Input bounds in the chain's order (lat, lon, h for geodetic input).
  const bool geo_in = detail::lon_first_in_files(o_.from);
  for (std::size_t k = 0; k < 3 && r.points; ++k) {
    const std::size_t file_axis = geo_in && k < 2 ? 1 - k : k;
    r.in_min[k] = in_qmin_[file_axis] * h.scale[file_axis] + h.offset[file_axis];
    r.in_max[k] = in_qmax_[file_axis] * h.scale[file_axis] + h.offset[file_axis];
  }
  return r;
}

}  // namespace

TileApplyResult apply_las_tile(const std::filesystem::path& in, std::ostream& out, const std::string& out_name,
                               const PointChain& chain, const TileApplyOptions& o) {
  LasTile tile(in, out, out_name, chain, o);
  return tile.run();
}

}  // namespace geoanchor::io
