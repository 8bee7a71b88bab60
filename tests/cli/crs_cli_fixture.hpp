#pragma once
// What the CRS command-line tests share (crs_cli_test.cpp,
// crs_las_cli_test.cpp): PROJ's C API as the independent reference, the
// CrsCli fixture that runs the real executable, the CRSs they go through.
// Test-only: one definition for every test file that includes it (inline).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <proj.h>
#include <proj_experimental.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>

#include "accuracy.hpp"
#include "cli_support.hpp"
#include "las_builder.hpp"
#include "proj_reference.hpp"
#include "geoanchor/base/number_text.hpp"
#include "test_support.hpp"

namespace geoanchor {
namespace crs_cli_fixture {

namespace fs = std::filesystem;
using testing::CliTest;
using testing::RunResult;
using testing::slurp;
using testing::WorstCase;
using nlohmann::json;

// Issue 13's acceptance: PROJ's own result on the same operation.
constexpr double kVsProjTol_m = 1e-6;
constexpr double kVsProjTol_deg = 1e-9;
constexpr std::size_t kPointsPerCrs = 100;
constexpr double kAreaMargin = 0.1;  // points stay this fraction of the area's span inside its bounding box
constexpr double kRadPerDeg = 0.017453292519943295;
constexpr double kRadPerGrad = 0.015707963267948967;

struct PjDel {
  void operator()(PJ* p) const { proj_destroy(p); }
};
using Pj = std::unique_ptr<PJ, PjDel>;

// A PROJ context of the test's own, independent of geoanchor's.
class Proj {
 public:
  Proj() : ctx_(proj_context_create()) {
    proj_log_level(ctx_, PJ_LOG_NONE);
    proj_context_set_enable_network(ctx_, 0);
  }
  ~Proj() { proj_context_destroy(ctx_); }
  Proj(const Proj&) = delete;
  Proj& operator=(const Proj&) = delete;
  PJ_CONTEXT* ctx() const { return ctx_; }
  Pj crs(const std::string& def) const { return Pj(proj_create(ctx_, def.c_str())); }
  // proj_create_crs_to_crs, normalised for visualisation; ballpark allowed
  // only for making test points.
  Pj op(const std::string& a, const std::string& b, bool ballpark = false) const {
    const char* opts[] = {ballpark ? "ALLOW_BALLPARK=YES" : "ALLOW_BALLPARK=NO", nullptr};
    Pj sa = crs(a), sb = crs(b);
    Pj raw(proj_create_crs_to_crs_from_pj(ctx_, sa.get(), sb.get(), nullptr, opts));
    return raw ? Pj(proj_normalize_for_visualization(ctx_, raw.get())) : Pj();
  }

 private:
  PJ_CONTEXT* ctx_;
};

// The column suffix of an axis unit, from the table in the issue (m, ft,
// ftus) and the angular units (deg, grad).
inline std::string unit_suffix(double factor, bool angular) {
  auto near = [](double a, double b) { return std::abs(a - b) <= 1e-12 * b; };
  if (angular) return near(factor, kRadPerDeg) ? "deg" : near(factor, kRadPerGrad) ? "grad" : "?";
  return near(factor, 1.0) ? "m" : near(factor, 0.3048) ? "ft" : near(factor, 1200.0 / 3937.0) ? "ftus" : "?";
}

struct Axes {
  std::vector<std::string> names;  // the CSV columns, visualisation order
  std::vector<double> to_si;       // per axis: metres or radians per unit
  bool geographic = false;
};

// The columns of a CRS as issue 13 defines them, from PROJ's normalised axes.
inline Axes columns_of(const Proj& p, const std::string& def) {
  Pj c = p.crs(def);
  Pj n(proj_normalize_for_visualization(p.ctx(), c.get()));
  Axes out;
  std::vector<Pj> parts;
  if (proj_get_type(n.get()) == PJ_TYPE_COMPOUND_CRS) {
    parts.emplace_back(proj_crs_get_sub_crs(p.ctx(), n.get(), 0));
    parts.emplace_back(proj_crs_get_sub_crs(p.ctx(), n.get(), 1));
  } else {
    parts.emplace_back(proj_clone(p.ctx(), n.get()));
  }
  const PJ_TYPE t = proj_get_type(parts[0].get());
  out.geographic = t == PJ_TYPE_GEOGRAPHIC_2D_CRS || t == PJ_TYPE_GEOGRAPHIC_3D_CRS;
  int k = 0;
  for (std::size_t part = 0; part < parts.size(); ++part) {
    Pj cs(proj_crs_get_coordinate_system(p.ctx(), parts[part].get()));
    for (int i = 0; i < proj_cs_get_axis_count(p.ctx(), cs.get()); ++i, ++k) {
      double f = 0;
      proj_cs_get_axis_info(p.ctx(), cs.get(), i, nullptr, nullptr, nullptr, &f, nullptr, nullptr, nullptr);
      const bool angular = out.geographic && k < 2;
      std::string stem = k == 0 ? (out.geographic ? "lon" : "easting") : k == 1 ? (out.geographic ? "lat" : "northing")
                                                                                 : (part == 1 ? "H" : "h");
      if (t == PJ_TYPE_GEOCENTRIC_CRS) stem = k == 0 ? "x" : k == 1 ? "y" : "z";
      out.names.push_back(stem + "_" + unit_suffix(f, angular));
      out.to_si.push_back(f);
    }
  }
  return out;
}

inline std::string fmt(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

using Csv = testing::CsvTable;
inline Csv parse_csv(const std::string& text) { return testing::parse_csv_table(text); }

// A row of the table written to docs/crs-acceptance.md.
struct TableRow {
  std::string code, name, method, units;
  double forward_m = 0, inverse_deg = 0;
  std::size_t points = 0;
};

class CrsCli : public CliTest {
 protected:
  // Random points inside the area of use of `code`, in `base` coordinates
  // (visualisation order), made with PROJ from longitude/latitude.
  std::vector<std::array<double, 3>> points_in_area(const std::string& code, const std::string& base, std::uint32_t seed) {
    Pj c = proj_.crs(code);
    double w = 0, s = 0, e = 0, n = 0;
    EXPECT_TRUE(proj_get_area_of_use(proj_.ctx(), c.get(), &w, &s, &e, &n, nullptr)) << code;
    return points_in_box(base, {w, s, e, n}, seed);
  }
  // The same inside a longitude/latitude box {west, south, east, north}.
  std::vector<std::array<double, 3>> points_in_box(const std::string& base, std::array<double, 4> box, std::uint32_t seed) {
    auto [w, s, e, n] = box;
    if (e < w) e += 360.0;
    const double dw = (e - w) * kAreaMargin, dn = (n - s) * kAreaMargin;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> lon(w + dw, e - dw), lat(s + dn, n - dn), h(-50.0, 3000.0);
    Pj to_base = proj_.op("OGC:CRS84", base, true);
    std::vector<std::array<double, 3>> out;
    for (std::size_t i = 0; i < kPointsPerCrs; ++i) {
      double x = lon(rng);
      if (x > 180.0) x -= 360.0;
      PJ_COORD cd = proj_coord(x, lat(rng), 0, 0);
      cd = proj_trans(to_base.get(), PJ_FWD, cd);
      out.push_back({cd.xyz.x, cd.xyz.y, h(rng)});
    }
    return out;
  }

  // geoanchor convert IN --crs A --to-crs B -o out.csv; the output table.
  Csv convert(const std::string& in_name, const std::string& a, const std::string& b, const std::string& extra = "") {
    const auto out = path("out_" + in_name);
    fs::remove(out);
    fs::remove(out.string() + ".geoanchor.json");
    const RunResult r = run("convert '" + path(in_name).string() + "' --crs '" + a + "' --to-crs '" + b + "' -o '" +
                            out.string() + "' " + extra);
    EXPECT_EQ(r.exit_code, 0) << a << " -> " << b << ": " << r.err;
    return parse_csv(slurp(out));
  }

  // Forward (geographic base → CRS, metres) and inverse (CRS → base,
  // degrees) worst differences from PROJ at random points.
  TableRow compare_conversion(const std::string& code, std::uint32_t seed) {
    Pj c = proj_.crs(code);
    Pj geodetic(proj_crs_get_geodetic_crs(proj_.ctx(), c.get()));
    const std::string base = std::string(proj_get_id_auth_name(geodetic.get(), 0)) + ":" + proj_get_id_code(geodetic.get(), 0);
    const Axes base_axes = columns_of(proj_, base), crs_axes = columns_of(proj_, code);
    auto pts = points_in_area(code, base, seed);

    std::ostringstream in;
    in << "id," << base_axes.names[0] << "," << base_axes.names[1] << "\n";
    for (std::size_t i = 0; i < pts.size(); ++i) in << "P" << i << "," << fmt(pts[i][0]) << "," << fmt(pts[i][1]) << "\n";
    write("fwd.csv", in.str());
    const Csv fwd = convert("fwd.csv", base, code);
    Pj op = proj_.op(base, code);
    TableRow row;
    row.code = code;
    row.name = proj_get_name(c.get());
    row.units = crs_axes.names[0] + ", " + crs_axes.names[1];
    Pj conv(proj_crs_get_coordoperation(proj_.ctx(), c.get()));
    const char* method = nullptr;
    proj_coordoperation_get_method_info(proj_.ctx(), conv.get(), &method, nullptr, nullptr);
    row.method = method ? method : "?";
    WorstCase forward, inverse;
    std::ostringstream back;
    back << "id," << crs_axes.names[0] << "," << crs_axes.names[1] << "\n";
    std::vector<std::array<double, 2>> projected;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      PJ_COORD r = proj_trans(op.get(), PJ_FWD, proj_coord(pts[i][0], pts[i][1], 0, 0));
      double de = std::numeric_limits<double>::quiet_NaN(), dn = de;
      if (i < fwd.rows.size()) {
        const auto got_e = parse_finite_double(fwd.rows[i][fwd.col(crs_axes.names[0])]);
        const auto got_n = parse_finite_double(fwd.rows[i][fwd.col(crs_axes.names[1])]);
        if (got_e && got_n) {
          de = std::abs(*got_e - r.xy.x) * crs_axes.to_si[0];
          dn = std::abs(*got_n - r.xy.y) * crs_axes.to_si[1];
        }
      }
      forward.add(testing::nan_max(de, dn), i);
      back << "P" << i << "," << fmt(r.xy.x) << "," << fmt(r.xy.y) << "\n";
      projected.push_back({r.xy.x, r.xy.y});
    }
    write("inv.csv", back.str());
    const Csv inv = convert("inv.csv", code, base);
    Pj iop = proj_.op(code, base);
    const double deg_per_unit = base_axes.to_si[0] / kRadPerDeg;
    for (std::size_t i = 0; i < projected.size(); ++i) {
      PJ_COORD r = proj_trans(iop.get(), PJ_FWD, proj_coord(projected[i][0], projected[i][1], 0, 0));
      double d = std::numeric_limits<double>::quiet_NaN();
      if (i < inv.rows.size()) {
        const auto lon = parse_finite_double(inv.rows[i][inv.col(base_axes.names[0])]);
        const auto lat = parse_finite_double(inv.rows[i][inv.col(base_axes.names[1])]);
        if (lon && lat) d = testing::nan_max(std::abs(*lon - r.lp.lam), std::abs(*lat - r.lp.phi)) * deg_per_unit;
      }
      inverse.add(d, i);
    }
    EXPECT_WORST_WITHIN(forward, kVsProjTol_m) << code << " forward";
    EXPECT_WORST_WITHIN(inverse, kVsProjTol_deg) << code << " inverse";
    row.forward_m = forward.value();
    row.inverse_deg = inverse.value();
    row.points = pts.size();
    return row;
  }

  Proj proj_;
};

// At least 40 projected CRSs from every continent, with the methods and
// units the issue names (State Plane TM and LCC in US survey feet, Lambert-93,
// RD New, LV95, Krovak, UPS, MGA2020, NZTM2000, a JGD2011 plane zone, a
// SIRGAS UTM zone, the British National Grid) and axis orders other than
// east/north (LAEA Europe, Gauss-Krüger, Japan, UPS, South Africa's Lo).
inline const std::vector<std::string> kProjectedCrs = {
    // North America
    "EPSG:2236", "EPSG:2227", "EPSG:2263", "EPSG:2252", "EPSG:26915", "EPSG:3978", "EPSG:2953", "EPSG:6350",
    "EPSG:3338", "EPSG:32145",
    // South America
    "EPSG:31983", "EPSG:5641", "EPSG:22185", "EPSG:32719",
    // Europe
    "EPSG:2154", "EPSG:28992", "EPSG:2056", "EPSG:5514", "EPSG:27700", "EPSG:25832", "EPSG:3035", "EPSG:31468",
    "EPSG:2180", "EPSG:3067", "EPSG:2100", "EPSG:3763", "EPSG:2157", "EPSG:3346", "EPSG:27572",
    // Africa
    "EPSG:2053", "EPSG:22391", "EPSG:21037", "EPSG:26331",
    // Asia
    "EPSG:6677", "EPSG:2326", "EPSG:3414", "EPSG:4547", "EPSG:5186", "EPSG:2039",
    // Oceania
    "EPSG:7856", "EPSG:7855", "EPSG:2193", "EPSG:3112",
    // Polar
    "EPSG:5042", "EPSG:32661", "EPSG:3031"};


}  // namespace crs_cli_fixture
}  // namespace geoanchor
