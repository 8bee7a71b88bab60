// LAS and LAZ tiles through a PointChain: X, Y, Z decoded to float64,
// transformed, and re-quantized at the output's scale and offset; every
// other byte of every record passes through. The points go in units of
// TileApplyOptions::laz_chunk_points records (a LAZ output's chunks): each
// unit is read (or decompressed), moved, quantized (and compressed) on any
// of the tile's threads, and the units are written in order by whichever
// thread finds the next one ready. At most two units per thread are in
// memory; the output and the error reported do not depend on the threads.

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <ctime>
#include <exception>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/gnss_solution.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/las/las.hpp"
#include "tile/las_record_source.hpp"
#include "tile/tile_common.hpp"

namespace geoanchor::io {
namespace {

using detail::Bounds;
using detail::RecordSource;

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

// The output's scale: the resolution in its units, the power of ten at or
// below it (0.01 US survey foot in, 0.001 m out; a resolution of 0.0025 m,
// 0.001 m), as apply.md states (issue 40 point 2).
std::array<double, 3> output_scale(const std::array<double, 2>& res, const ArrayFrame& to, const std::optional<TileCrsAxes>& crs) {
  if (crs && !crs->geocentric) {
    const double z = pow10_floor(res[1] / crs->vertical_m);
    if (crs->angular) {
      const double unit = pow10_floor(res[0] / kMetresPerDegree / crs->horizontal_unit);
      return {unit, unit, z};
    }
    const double xy = pow10_floor(res[0] / crs->horizontal_unit);
    return {xy, xy, z};
  }
  if (!crs && to.kind == CoordinateKind::geodetic) {
    const double deg = pow10_floor(res[0] / kMetresPerDegree);
    return {deg, deg, pow10_floor(res[1])};
  }
  if (crs || to.kind == CoordinateKind::ecef) {
    const double r = pow10_floor(std::min(res[0], res[1]));
    return {r, r, r};
  }
  return {pow10_floor(res[0]), pow10_floor(res[0]), pow10_floor(res[1])};
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
// A unit after one that failed: not processed (never reported: the writer
// stops at the failed one).
struct AfterFailure {};

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

using Bytes = std::vector<std::uint8_t>;
using Int3 = std::array<std::int32_t, 3>;
constexpr Int3 kInt3Max{INT32_MAX, INT32_MAX, INT32_MAX};
constexpr Int3 kInt3Min{INT32_MIN, INT32_MIN, INT32_MIN};

// What a pass does with each unit's moved points.
enum class PassKind {
  write,   // quantize, scatter into the records, compress (LAZ), write
  bounds,  // only the output's bounds (the int32-overflow retry)
};

// One unit's outcome, held until it is written in order.
struct Unit {
  std::uint64_t index = 0;
  bool ready = false;
  std::exception_ptr error;
  std::size_t n = 0;
  Bytes records;  // LAS output: what is written
  Bytes chunk;    // LAZ output: the compressed chunk
  Int3 in_qmin = kInt3Max, in_qmax = kInt3Min, qmin = kInt3Max, qmax = kInt3Min;
  double epoch_lo = std::numeric_limits<double>::infinity(), epoch_hi = -std::numeric_limits<double>::infinity();
  Bounds bounds;
  UtmBandTally band_in, band_out;
  std::string band_in_where, band_out_where;
  std::array<std::uint64_t, geodesy::kGnssSolutionCount> solutions{};  // points per GNSS solution type
};

// One thread's work space, reused from unit to unit.
struct Scratch {
  std::vector<double> x, y, z, epochs;
  std::vector<std::int32_t> q;
  std::optional<LazChunkEncoder> encoder;
};

class LasTile {
 public:
  LasTile(const std::filesystem::path& in, std::ostream& out, std::string out_name, const PointChain& chain,
          const TileApplyOptions& o)
      : reader_(in), out_(out), out_name_(std::move(out_name)), chain_(chain), o_(o),
        unit_points_(std::max<std::uint32_t>(o.laz_chunk_points, 1)), source_(reader_, unit_points_) {}

  TileApplyResult run();

 private:
  // Every point in units on o_.threads threads: each unit read, its X, Y, Z
  // decoded and moved, then (write) quantized at `scale`/`offset` and
  // handed to `writer` in order, or (bounds) its output bounds gathered.
  // Throws the error of the first unit (in point order) that failed, and
  // Overflow for a value that does not fit int32.
  void pass(PassKind kind, LasWriter* writer, const std::array<double, 3>& scale, const std::array<double, 3>& offset);
  // One unit, on any thread.
  void process(PassKind kind, const LasWriter* writer, const std::array<double, 3>& scale,
               const std::array<double, 3>& offset, Unit& u, Scratch& s);
  // Where point `p` (0-based) is in the input, for messages: "point N (byte
  // B)" for LAS, "point N (chunk I at byte B)" for LAZ.
  std::string point_name(std::uint64_t p) const;
  // The CRS stages keep state (per-point choices counted, the first point
  // outside an area named): they run on one unit at a time, in order, and
  // not after a unit that failed. wait_crs_turn: false after a failure.
  bool wait_crs_turn(std::uint64_t unit);
  void pass_crs_turn(std::uint64_t unit, bool failed);
  // The steps of run().
  void check_records(const LasHeader& h);
  void choose_scale_and_offset(const LasHeader& h, TileApplyResult& r);
  std::pair<std::vector<LasVlr>, std::vector<LasVlr>> output_vlrs(TileApplyResult& r) const;
  LasHeader output_header(const LasHeader& h, const TileApplyResult& r) const;
  void write_points(std::optional<LasWriter>& writer, LasHeader& oh, const std::vector<LasVlr>& vlrs,
                    const std::vector<LasVlr>& evlrs, const LasCompression& compression, TileApplyResult& r);

  LasReader reader_;
  std::ostream& out_;
  std::string out_name_;
  const PointChain& chain_;
  const TileApplyOptions& o_;
  const std::uint32_t unit_points_;
  RecordSource source_;
  std::size_t gps_time_offset_ = 0;
  std::optional<std::size_t> solution_offset_;  // the "gnss_solution" extra byte in a record
  std::array<std::uint64_t, geodesy::kGnssSolutionCount> solutions_{};
  // Gathered over a pass, in point order.
  double epoch_lo_ = std::numeric_limits<double>::infinity(), epoch_hi_ = -std::numeric_limits<double>::infinity();
  Int3 in_qmin_ = kInt3Max, in_qmax_ = kInt3Min, qmin_ = kInt3Max, qmax_ = kInt3Min;
  Bounds bounds_;
  UtmBandTally band_in_, band_out_;  // of the last pass: points outside a UTM zone's band
  std::mutex crs_m_;
  std::condition_variable crs_cv_;
  std::uint64_t crs_next_ = 0;
  bool crs_failed_ = false;
};

std::string LasTile::point_name(std::uint64_t p) const {
  const LasHeader& h = reader_.header();
  if (!reader_.compressed()) {
    return "point " + std::to_string(p + 1) + " (byte " + std::to_string(h.offset_to_points + p * h.record_length) + ")";
  }
  const std::size_t c = source_.chunk_of(p);
  return "point " + std::to_string(p + 1) + " (chunk " + std::to_string(c) + " at byte " +
         std::to_string(reader_.chunk_offset(c)) + ")";
}

bool LasTile::wait_crs_turn(std::uint64_t unit) {
  std::unique_lock<std::mutex> lock(crs_m_);
  crs_cv_.wait(lock, [&] { return crs_next_ == unit; });
  return !crs_failed_;
}

void LasTile::pass_crs_turn(std::uint64_t unit, bool failed) {
  {
    const std::lock_guard<std::mutex> lock(crs_m_);
    crs_next_ = unit + 1;
    crs_failed_ = crs_failed_ || failed;
  }
  crs_cv_.notify_all();
}

void LasTile::process(PassKind kind, const LasWriter* writer, const std::array<double, 3>& scale,
                      const std::array<double, 3>& offset, Unit& u, Scratch& s) {
  const LasHeader& h = reader_.header();
  const std::size_t len = h.record_length;
  const std::uint64_t done = u.index * unit_points_;
  const std::size_t n = u.n;
  const bool crs_stages = !o_.keep_coordinates && (o_.crs_before || o_.crs_after);
  // Every unit takes its turn at the CRS stages, even one that fails first,
  // so that the units after it are not kept waiting; after a unit failed,
  // the units after it do not run them (as one thread stops at the first
  // error), so that what the stages count and name is the same on any
  // number of threads.
  struct CrsTurn {
    LasTile& tile;
    std::uint64_t unit;
    bool active, taken = false;
    int exceptions = std::uncaught_exceptions();
    void take() {
      if (active && !taken) {
        taken = true;
        if (!tile.wait_crs_turn(unit)) throw AfterFailure{};
      }
    }
    ~CrsTurn() {
      if (!active) return;
      if (!taken) {
        taken = true;
        (void)tile.wait_crs_turn(unit);
      }
      tile.pass_crs_turn(unit, std::uncaught_exceptions() > exceptions);
    }
  } turn{*this, u.index, crs_stages};

  source_.fetch(done, n, u.records);
  s.x.resize(n);
  s.y.resize(n);
  s.z.resize(n);
  {
    const std::uint8_t* p = u.records.data();
    double* xs = s.x.data();
    double* ys = s.y.data();
    double* zs = s.z.data();
    const double sx = h.scale[0], sy = h.scale[1], sz = h.scale[2];
    const double ox = h.offset[0], oy = h.offset[1], oz = h.offset[2];
    std::int32_t lo0 = INT32_MAX, lo1 = INT32_MAX, lo2 = INT32_MAX;
    std::int32_t hi0 = INT32_MIN, hi1 = INT32_MIN, hi2 = INT32_MIN;
    for (std::size_t i = 0; i < n; ++i, p += len) {
      std::int32_t q[3];
      std::memcpy(q, p, sizeof q);
      lo0 = std::min(lo0, q[0]), hi0 = std::max(hi0, q[0]);
      lo1 = std::min(lo1, q[1]), hi1 = std::max(hi1, q[1]);
      lo2 = std::min(lo2, q[2]), hi2 = std::max(hi2, q[2]);
      xs[i] = q[0] * sx + ox;
      ys[i] = q[1] * sy + oy;
      zs[i] = q[2] * sz + oz;
    }
    u.in_qmin = {lo0, lo1, lo2};
    u.in_qmax = {hi0, hi1, hi2};
  }
  if (o_.epochs_from_gps_time) {
    // Adjusted standard GPS time: GPS seconds minus 1e9.
    s.epochs.resize(n);
    const std::uint8_t* g = u.records.data() + gps_time_offset_;
    for (std::size_t i = 0; i < n; ++i, g += len) {
      double adjusted = 0.0;
      std::memcpy(&adjusted, g, sizeof adjusted);
      if (!std::isfinite(adjusted)) {
        throw Error(ErrorKind::input, "E_GPS_TIME",
                    reader_.path().string() + ": " + point_name(done + i) + " has a non-finite GPS time");
      }
      s.epochs[i] = geodesy::decimal_year_from_gps_seconds(adjusted + 1.0e9).year;
      u.epoch_lo = std::min(u.epoch_lo, s.epochs[i]);
      u.epoch_hi = std::max(u.epoch_hi, s.epochs[i]);
    }
  }

  if (solution_offset_) {
    // Each point's GNSS solution type (extra byte "gnss_solution"): counted,
    // and a code outside the table refused by point.
    const std::uint8_t* g = u.records.data() + *solution_offset_;
    for (std::size_t i = 0; i < n; ++i, g += len) {
      const auto solution = geodesy::gnss_solution_from_code(*g);
      if (!solution) {
        throw Error(ErrorKind::input, "E_GNSS_SOLUTION",
                    reader_.path().string() + ": " + point_name(done + i) + ": extra byte gnss_solution = " +
                        std::to_string(*g) + " is no GNSS solution code; expected 1 fixed, 2 ppk, 3 float, 4 dgps, "
                        "5 sbas, 6 standalone, 7 dead_reckoned");
      }
      ++u.solutions[geodesy::solution_index(*solution)];
    }
  }
  if (o_.keep_coordinates) {
    // The tile's own coordinates: the records are the output.
    u.qmin = u.in_qmin;
    u.qmax = u.in_qmax;
  } else {
    const bool geo_in = detail::lon_first_in_files(o_.from);
    const bool geo_out = detail::lon_first_in_files(o_.to);
    // Chain order: (lat, lon, h) for geodetic, (X, Y, Z) otherwise.
    std::span<double> a(geo_in ? s.y.data() : s.x.data(), n);
    std::span<double> b(geo_in ? s.x.data() : s.y.data(), n);
    std::span<double> c(s.z.data(), n);
    auto name = [&](std::size_t i) { return point_name(done + i); };
    turn.take();
    const ChainReport report = detail::move_points(chain_, o_, a, b, c, o_.epochs_from_gps_time ? &s.epochs : nullptr, name);
    // The chain wrote the output in its order into the same arrays.
    std::span<double> xs = geo_out ? b : a;
    std::span<double> ys = geo_out ? a : b;
    if (const std::size_t bad = detail::first_non_finite(xs, ys, c); bad < n) {
      throw Error(ErrorKind::input, "E_TRANSFORM",
                  reader_.path().string() + ": " + name(bad) + " has no finite position in the output frame" +
                      detail::refusal_reason(report, bad) + "; nothing was written");
    }
    u.band_in = report.input_band;
    u.band_out = report.output_band;
    if (u.band_in.points) u.band_in_where = name(u.band_in.worst_index);
    if (u.band_out.points) u.band_out_where = name(u.band_out.worst_index);
    if (kind == PassKind::bounds) {
      u.bounds.add(xs, ys, c);
      return;
    }
    s.q.resize(3 * n);
    const std::span<double> axes[3] = {xs, ys, c};
    for (std::size_t k = 0; k < 3; ++k) {
      const double* v = axes[k].data();
      std::int32_t* q = s.q.data() + k * n;
      const double off = offset[k], inv = 1.0 / scale[k];
      if (!quantize(v, q, n, off, inv, u.qmin[k], u.qmax[k])) {
        for (std::size_t i = 0; i < n; ++i) {
          const double t = (v[i] - off) * inv;
          if (!(t > kInt32Min - 0.5 && t < kInt32Max + 0.5)) throw Overflow{done + i + 1, static_cast<int>(k), v[i]};
        }
      }
    }
    // Scatter X, Y, Z into the records; every other byte stays.
    const std::int32_t* qx = s.q.data();
    const std::int32_t* qy = qx + n;
    const std::int32_t* qz = qy + n;
    std::uint8_t* p = u.records.data();
    for (std::size_t i = 0; i < n; ++i, p += len) {
      const std::int32_t xyz[3] = {qx[i], qy[i], qz[i]};
      std::memcpy(p, xyz, sizeof xyz);
    }
  }
  if (kind == PassKind::write && writer->compressed()) {
    if (!s.encoder) s.encoder.emplace(*writer->laz());
    if (n) s.encoder->encode(u.records.data(), n, u.chunk);
  }
}

void LasTile::pass(PassKind kind, LasWriter* writer, const std::array<double, 3>& scale,
                   const std::array<double, 3>& offset) {
  const std::uint64_t total = reader_.header().point_count;
  const std::uint64_t units = (total + unit_points_ - 1) / unit_points_;
  const unsigned threads = static_cast<unsigned>(std::clamp<std::uint64_t>(o_.threads, 1, std::max<std::uint64_t>(units, 1)));
  const std::size_t window = 2 * std::size_t{threads};
  band_in_ = band_out_ = UtmBandTally{};
  solutions_ = {};
  bounds_ = Bounds{};
  qmin_ = kInt3Max;
  qmax_ = kInt3Min;
  crs_next_ = 0;
  crs_failed_ = false;

  std::vector<Unit> slots(window);
  std::mutex m;
  std::condition_variable cv;
  std::uint64_t next_unit = 0, next_write = 0;
  bool writing = false, stop = false;
  std::exception_ptr failure;

  // In order, on whichever thread finds the next unit ready: merge and write.
  auto write_unit = [&](Unit& u) {
    for (std::size_t k = 0; k < 3; ++k) {
      in_qmin_[k] = std::min(in_qmin_[k], u.in_qmin[k]);
      in_qmax_[k] = std::max(in_qmax_[k], u.in_qmax[k]);
      qmin_[k] = std::min(qmin_[k], u.qmin[k]);
      qmax_[k] = std::max(qmax_[k], u.qmax[k]);
      bounds_.min[k] = std::min(bounds_.min[k], u.bounds.min[k]);
      bounds_.max[k] = std::max(bounds_.max[k], u.bounds.max[k]);
    }
    epoch_lo_ = std::min(epoch_lo_, u.epoch_lo);
    epoch_hi_ = std::max(epoch_hi_, u.epoch_hi);
    for (std::size_t k = 0; k < solutions_.size(); ++k) solutions_[k] += u.solutions[k];
    band_in_.absorb(u.band_in, u.band_in_where);
    band_out_.absorb(u.band_out, u.band_out_where);
    if (kind == PassKind::write) {
      if (writer->compressed()) {
        writer->write_chunk(u.chunk, u.n);
      } else {
        writer->write_records(u.records.data(), u.n);
      }
    }
    if (o_.progress) o_.progress(u.index * unit_points_ + u.n);
  };

  auto worker = [&] {
    Scratch scratch;
    for (;;) {
      Unit* u = nullptr;
      {
        std::unique_lock<std::mutex> lock(m);
        cv.wait(lock, [&] { return stop || next_unit >= units || next_unit < next_write + window; });
        if (stop || next_unit >= units) return;
        const std::uint64_t k = next_unit++;
        u = &slots[static_cast<std::size_t>(k % window)];
        u->index = k;
        u->ready = false;
        u->error = nullptr;
        u->n = static_cast<std::size_t>(std::min<std::uint64_t>(unit_points_, total - k * unit_points_));
        u->in_qmin = u->qmin = kInt3Max;
        u->in_qmax = u->qmax = kInt3Min;
        u->epoch_lo = std::numeric_limits<double>::infinity();
        u->epoch_hi = -std::numeric_limits<double>::infinity();
        u->bounds = Bounds{};
        u->band_in = u->band_out = UtmBandTally{};
        u->solutions = {};
      }
      try {
        process(kind, writer, scale, offset, *u, scratch);
      } catch (...) {
        u->error = std::current_exception();
      }
      std::unique_lock<std::mutex> lock(m);
      u->ready = true;
      if (writing) continue;  // the thread writing will come to it
      writing = true;
      while (!stop && next_write < units) {
        Unit& w = slots[static_cast<std::size_t>(next_write % window)];
        if (!w.ready || w.index != next_write) break;
        if (w.error) {
          failure = w.error;
          stop = true;
          break;
        }
        lock.unlock();
        try {
          write_unit(w);
        } catch (...) {
          lock.lock();
          failure = std::current_exception();
          stop = true;
          break;
        }
        lock.lock();
        w.ready = false;
        ++next_write;
        cv.notify_all();
      }
      writing = false;
      if (stop) cv.notify_all();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(threads);
  for (unsigned t = 1; t < threads; ++t) {
    try {
      pool.emplace_back(worker);
    } catch (...) {  // std::system_error, std::bad_alloc: never unwind past running threads
      break;  // a thread that cannot start leaves its units to the others
    }
  }
  worker();
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

// What the tile's kind and records must carry: ENU (not NED) coordinates,
// GPS times that say the week for per-point epochs, and a GNSS solution
// code as an unscaled uint8 extra byte.
void LasTile::check_records(const LasHeader& h) {
  for (const ArrayFrame* f : {&o_.from, &o_.to}) {
    if (!o_.keep_coordinates && f->kind == CoordinateKind::ned) {
      throw Error(ErrorKind::usage, "E_TILE_KIND", reader_.path().string() + ": LAS tiles are ENU, not NED");
    }
  }
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
  for (const auto& a : las_extra_bytes(reader_.vlrs(), h.point_format, h.record_length, reader_.path().string())) {
    if (a.name != kGnssSolutionAttribute) continue;
    const bool scaled = (a.options & 0x18u) != 0;  // bits 3, 4: scale, offset
    if (a.data_type != 1 || scaled) {
      throw Error(ErrorKind::input, "E_LAS_EXTRA_BYTES",
                  reader_.path().string() + ": extra-bytes attribute '" + a.name + "' has data type " +
                      std::to_string(a.data_type) + (scaled ? " with a scale or offset" : "") +
                      "; a GNSS solution code is an unscaled uint8 (data type 1)");
    }
    solution_offset_ = a.offset;
  }
}

// Scale and offset of the output's coordinates.
void LasTile::choose_scale_and_offset(const LasHeader& h, TileApplyResult& r) {
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
}

// The output's VLRs and EVLRs.
std::pair<std::vector<LasVlr>, std::vector<LasVlr>> LasTile::output_vlrs(TileApplyResult& r) const {
  // VLRs: every one but the old CRS (WKT or GeoTIFF), which the new WKT
  // replaces, and a COPC file's records, which describe an octree layout
  // the output does not have. The new WKT is the first VLR.
  LasVlr wkt;
  wkt.user_id = "LASF_Projection";
  wkt.record_id = kLasWktRecordId;
  wkt.description = "OGC WKT2:2019 CRS (geoanchor)";
  wkt.data.assign(o_.output_wkt.begin(), o_.output_wkt.end());
  wkt.data.push_back(0);
  std::vector<LasVlr> vlrs, evlrs;
  vlrs.push_back(std::move(wkt));
  bool dropped_crs = false, dropped_copc = false;
  for (const auto& v : reader_.vlrs()) {
    if (is_wkt_crs_vlr(v) || is_geotiff_crs_vlr(v)) {
      dropped_crs = true;
      continue;
    }
    if (v.user_id == "copc") {
      dropped_copc = true;
      continue;
    }
    (v.extended ? evlrs : vlrs).push_back(v);
  }
  if (dropped_crs) r.warnings.push_back(reader_.path().string() + ": the input's CRS records were replaced by the output's WKT");
  if (dropped_copc) {
    r.warnings.push_back(reader_.path().string() + ": a COPC file, written as plain " +
                         std::string(o_.las_output == TileFormat::laz ? "LAZ" : "LAS") +
                         ": geoanchor does not write COPC's octree hierarchy, so its 'copc' records (info VLR, "
                         "hierarchy EVLR) were dropped; the points keep their order");
  }
  return {std::move(vlrs), std::move(evlrs)};
}

// The input's header with the output's WKT bit, software, date, scale and offset.
LasHeader LasTile::output_header(const LasHeader& h, const TileApplyResult& r) const {
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
  return oh;
}

// Every point through a write pass; on an int32 overflow, once more from the
// middle of the output's true bounds.
void LasTile::write_points(std::optional<LasWriter>& writer, LasHeader& oh, const std::vector<LasVlr>& vlrs,
                           const std::vector<LasVlr>& evlrs, const LasCompression& compression, TileApplyResult& r) {
  const bool laz = compression.laz;
  try {
    pass(PassKind::write, &*writer, r.scale, r.offset);
  } catch (const Overflow&) {
    // The header's bounds were wrong (or the chain bends them): take the
    // true bounds of the output and try once more from the middle of them.
    pass(PassKind::bounds, nullptr, r.scale, r.offset);
    const Bounds exact = bounds_;
    for (std::size_t k = 0; k < 3; ++k) r.offset[k] = centred_offset(exact.min[k], exact.max[k], r.scale[k]);
    oh.offset = r.offset;
    if (laz) {
      // A LAZ pass has another length: the tile again from its first byte.
      if (!o_.restart_output) {
        throw std::logic_error(out_name_ + ": the int32-overflow retry of a LAZ output needs TileApplyOptions::restart_output");
      }
      writer.reset();
      writer.emplace(o_.restart_output(), oh, vlrs, evlrs, out_name_, compression);
    } else {
      writer->restart(r.offset);  // the same length: rewritten in place
    }
    try {
      pass(PassKind::write, &*writer, r.scale, r.offset);
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
}

TileApplyResult LasTile::run() {
  const LasHeader& h = reader_.header();
  check_records(h);
  TileApplyResult r;
  r.points = h.point_count;
  r.storage = "int32_scaled";

  if (o_.keep_coordinates) {
    r.scale = h.scale;
    r.offset = h.offset;
  } else {
    choose_scale_and_offset(h, r);
  }

  const auto [vlrs, evlrs] = output_vlrs(r);

  LasHeader oh = output_header(h, r);
  const bool laz = o_.las_output == TileFormat::laz;
  const LasCompression compression{laz, unit_points_};
  std::optional<LasWriter> writer;
  writer.emplace(out_, oh, vlrs, evlrs, out_name_, compression);

  write_points(writer, oh, vlrs, evlrs, compression, r);
  for (std::size_t k = 0; k < 3; ++k) {
    r.min[k] = r.points ? static_cast<double>(qmin_[k]) * r.scale[k] + r.offset[k] : 0.0;
    r.max[k] = r.points ? static_cast<double>(qmax_[k]) * r.scale[k] + r.offset[k] : 0.0;
  }
  if (laz) r.laz = *writer->laz();
  writer->finish(h.points_by_return, r.min, r.max);
  detail::add_band_warnings(r, reader_.path().string(), band_in_, band_out_);
  if (o_.epochs_from_gps_time && r.points) r.epoch_range = std::array<double, 2>{epoch_lo_, epoch_hi_};
  if (solution_offset_) r.gnss_solution_counts = solutions_;
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
