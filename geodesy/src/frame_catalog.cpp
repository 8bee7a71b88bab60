#include "geoanchor/geodesy/frame_catalog.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <set>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/base/number_text.hpp"

namespace geoanchor::geodesy {
namespace {

// One row of an IERS table: translations (mm), scale (ppb), rotations (mas)
// at the epoch, and their rates per year.
struct IersRow {
  const char* to;
  double tx, ty, tz, d, rx, ry, rz;
  double dtx, dty, dtz, dd, drx, dry, drz;
  double accuracy_m;
  const char* epsg;  // the EPSG operation in the opposite direction
};

CatalogTransformation from_iers(const char* from, double epoch, const IersRow& r, const std::string& table,
                                bool epsg_reversed = true) {
  CatalogTransformation c;
  c.from = from;
  c.to = r.to;
  auto& p = c.params.at_reference_epoch;
  p.t_m = 1e-3 * Eigen::Vector3d(r.tx, r.ty, r.tz);
  p.rx = Angle::milliarcseconds(r.rx);
  p.ry = Angle::milliarcseconds(r.ry);
  p.rz = Angle::milliarcseconds(r.rz);
  p.ds = ScaleDifference::ppb(r.d);
  auto& v = c.params.rates;
  v.dt_m_per_year = 1e-3 * Eigen::Vector3d(r.dtx, r.dty, r.dtz);
  v.drx_per_year = Angle::milliarcseconds(r.drx);
  v.dry_per_year = Angle::milliarcseconds(r.dry);
  v.drz_per_year = Angle::milliarcseconds(r.drz);
  v.dds_per_year = ScaleDifference::ppb(r.dd);
  c.params.reference_epoch = DecimalYear{epoch};
  c.accuracy_m = r.accuracy_m;
  c.source = table;
  c.epsg = r.epsg;
  c.epsg_reversed = epsg_reversed;
  return c;
}

// The rates shared by the rows for ITRF97 and the realizations before it.
#define ITRF2020_OLD_RATES 0.1, -0.6, -3.1, 0.12, 0.00, 0.00, 0.02
#define ITRF2014_OLD_RATES 0.1, -0.5, -3.3, 0.12, 0.00, 0.00, 0.02
#define ITRF2008_OLD_RATES 0.1, -0.5, -3.2, 0.09, 0.00, 0.00, 0.02

// The IERS sets between ITRF realizations.
void add_itrf_sets(std::vector<CatalogTransformation>& out) {
  // IERS (Altamimi et al.), "Transformation parameters from ITRF2020 to past
  // ITRFs", itrf.ign.fr/docs/solutions/itrf2020/Transfo-ITRF2020_TRFs.txt
  // (2022); epoch 2015.0; XS = X + T + D·X + R·X (position vector).
  const std::string t2020 = "IERS, Transfo-ITRF2020_TRFs.txt (ITRF2020 to past ITRFs, epoch 2015.0)";
  static constexpr IersRow kFrom2020[] = {
      {"ITRF2014", -1.4, -0.9, 1.4, -0.42, 0.00, 0.00, 0.00, 0.0, -0.1, 0.2, 0.00, 0.00, 0.00, 0.00, 0.001, "EPSG:9991"},
      {"ITRF2008", 0.2, 1.0, 3.3, -0.29, 0.00, 0.00, 0.00, 0.0, -0.1, 0.1, 0.03, 0.00, 0.00, 0.00, 0.01, "EPSG:9992"},
      {"ITRF2005", 2.7, 0.1, -1.4, 0.65, 0.00, 0.00, 0.00, 0.3, -0.1, 0.1, 0.03, 0.00, 0.00, 0.00, 0.01, "EPSG:9993"},
      {"ITRF2000", -0.2, 0.8, -34.2, 2.25, 0.00, 0.00, 0.00, 0.1, 0.0, -1.7, 0.11, 0.00, 0.00, 0.00, 0.01, "EPSG:9994"},
      {"ITRF97", 6.5, -3.9, -77.9, 3.98, 0.00, 0.00, 0.36, ITRF2020_OLD_RATES, 0.01, "EPSG:9995"},
      {"ITRF96", 6.5, -3.9, -77.9, 3.98, 0.00, 0.00, 0.36, ITRF2020_OLD_RATES, 0.01, "EPSG:9996"},
      {"ITRF94", 6.5, -3.9, -77.9, 3.98, 0.00, 0.00, 0.36, ITRF2020_OLD_RATES, 0.01, "EPSG:9997"},
      {"ITRF93", -65.8, 1.9, -71.3, 4.47, -3.36, -4.33, 0.75, -2.8, -0.2, -2.3, 0.12, -0.11, -0.19, 0.07, 0.01, "EPSG:9998"},
      {"ITRF92", 14.5, -1.9, -85.9, 3.27, 0.00, 0.00, 0.36, ITRF2020_OLD_RATES, 0.01, "EPSG:9999"},
      {"ITRF91", 26.5, 12.1, -91.9, 4.67, 0.00, 0.00, 0.36, ITRF2020_OLD_RATES, 0.01, "EPSG:10100"},
      {"ITRF90", 24.5, 8.1, -107.9, 4.97, 0.00, 0.00, 0.36, ITRF2020_OLD_RATES, 0.01, "EPSG:10103"},
      {"ITRF89", 29.5, 32.1, -145.9, 8.37, 0.00, 0.00, 0.36, ITRF2020_OLD_RATES, 0.01, "EPSG:10104"},
      {"ITRF88", 24.5, -3.9, -169.9, 11.47, 0.10, 0.00, 0.36, ITRF2020_OLD_RATES, 0.01, "EPSG:10105"},
  };
  for (const auto& r : kFrom2020) out.push_back(from_iers("ITRF2020", 2015.0, r, t2020));

  // IERS, "Transformation parameters from ITRF2014 to past ITRFs",
  // itrf.ign.fr/doc_ITRF/Transfo-ITRF2014_ITRFs.txt (2016); epoch 2010.0.
  const std::string t2014 = "IERS, Transfo-ITRF2014_ITRFs.txt (ITRF2014 to past ITRFs, epoch 2010.0)";
  static constexpr IersRow kFrom2014[] = {
      {"ITRF2008", 1.6, 1.9, 2.4, -0.02, 0.00, 0.00, 0.00, 0.0, 0.0, -0.1, 0.03, 0.00, 0.00, 0.00, 0.01, "EPSG:7790"},
      {"ITRF2005", 2.6, 1.0, -2.3, 0.92, 0.00, 0.00, 0.00, 0.3, 0.0, -0.1, 0.03, 0.00, 0.00, 0.00, 0.01, "EPSG:8079"},
      {"ITRF2000", 0.7, 1.2, -26.1, 2.12, 0.00, 0.00, 0.00, 0.1, 0.1, -1.9, 0.11, 0.00, 0.00, 0.00, 0.01, "EPSG:8078"},
      {"ITRF97", 7.4, -0.5, -62.8, 3.80, 0.00, 0.00, 0.26, ITRF2014_OLD_RATES, 0.01, "EPSG:8077"},
      {"ITRF96", 7.4, -0.5, -62.8, 3.80, 0.00, 0.00, 0.26, ITRF2014_OLD_RATES, 0.01, "EPSG:8076"},
      {"ITRF94", 7.4, -0.5, -62.8, 3.80, 0.00, 0.00, 0.26, ITRF2014_OLD_RATES, 0.01, "EPSG:8075"},
      {"ITRF93", -50.4, 3.3, -60.2, 4.29, -2.81, -3.38, 0.40, -2.8, -0.1, -2.5, 0.12, -0.11, -0.19, 0.07, 0.01, "EPSG:8074"},
      {"ITRF92", 15.4, 1.5, -70.8, 3.09, 0.00, 0.00, 0.26, ITRF2014_OLD_RATES, 0.01, "EPSG:8073"},
      {"ITRF91", 27.4, 15.5, -76.8, 4.49, 0.00, 0.00, 0.26, ITRF2014_OLD_RATES, 0.01, "EPSG:8072"},
      {"ITRF90", 25.4, 11.5, -92.8, 4.79, 0.00, 0.00, 0.26, ITRF2014_OLD_RATES, 0.01, "EPSG:8071"},
      {"ITRF89", 30.4, 35.5, -130.8, 8.19, 0.00, 0.00, 0.26, ITRF2014_OLD_RATES, 0.01, "EPSG:8070"},
      {"ITRF88", 25.4, -0.5, -154.8, 11.29, 0.10, 0.00, 0.26, ITRF2014_OLD_RATES, 0.01, "EPSG:8069"},
  };
  for (const auto& r : kFrom2014) out.push_back(from_iers("ITRF2014", 2010.0, r, t2014));

  // IERS, "Transformation parameters from ITRF2008 to past ITRFs",
  // itrf.ign.fr/doc_ITRF/Transfo-ITRF2008_ITRFs.txt; epoch 2000.0.
  const std::string t2008 = "IERS, Transfo-ITRF2008_ITRFs.txt (ITRF2008 to past ITRFs, epoch 2000.0)";
  static constexpr IersRow kFrom2008[] = {
      {"ITRF2005", -2.0, -0.9, -4.7, 0.94, 0.00, 0.00, 0.00, 0.3, 0.0, 0.0, 0.00, 0.00, 0.00, 0.00, 0.01, "EPSG:6389"},
      {"ITRF2000", -1.9, -1.7, -10.5, 1.34, 0.00, 0.00, 0.00, 0.1, 0.1, -1.8, 0.08, 0.00, 0.00, 0.00, 0.01, "EPSG:6300"},
      {"ITRF97", 4.8, 2.6, -33.2, 2.92, 0.00, 0.00, 0.06, ITRF2008_OLD_RATES, 0.01, "EPSG:6299"},
      {"ITRF96", 4.8, 2.6, -33.2, 2.92, 0.00, 0.00, 0.06, ITRF2008_OLD_RATES, 0.01, "EPSG:6298"},
      {"ITRF94", 4.8, 2.6, -33.2, 2.92, 0.00, 0.00, 0.06, ITRF2008_OLD_RATES, 0.01, "EPSG:6297"},
      {"ITRF93", -24.0, 2.4, -38.6, 3.41, -1.71, -1.48, -0.30, -2.8, -0.1, -2.4, 0.09, -0.11, -0.19, 0.07, 0.01, "EPSG:6296"},
      {"ITRF92", 12.8, 4.6, -41.2, 2.21, 0.00, 0.00, 0.06, ITRF2008_OLD_RATES, 0.01, "EPSG:6295"},
      {"ITRF91", 24.8, 18.6, -47.2, 3.61, 0.00, 0.00, 0.06, ITRF2008_OLD_RATES, 0.01, "EPSG:6294"},
      {"ITRF90", 22.8, 14.6, -63.2, 3.91, 0.00, 0.00, 0.06, ITRF2008_OLD_RATES, 0.01, "EPSG:6293"},
      {"ITRF89", 27.8, 38.6, -101.2, 7.31, 0.00, 0.00, 0.06, ITRF2008_OLD_RATES, 0.01, "EPSG:6292"},
      {"ITRF88", 22.8, 2.6, -125.2, 10.41, 0.10, 0.00, 0.06, ITRF2008_OLD_RATES, 0.01, "EPSG:6291"},
  };
  for (const auto& r : kFrom2008) out.push_back(from_iers("ITRF2008", 2000.0, r, t2008));
}

// The EUREF sets from ITRF realizations to ETRF ones.
void add_etrf_sets(std::vector<CatalogTransformation>& out) {
  // EUREF Technical Note 1 (Altamimi, "Relationship and transformation
  // between the International and the European Terrestrial Reference
  // Systems"): each ETRFyy from its ITRFyy by the rotation of stable Eurasia
  // since 1989.0 (plus the translations of the early realizations), and
  // ETRF2000 from the later ITRFs. ETRS89 realizations are defined by these
  // sets, hence no stated error (EPSG gives 0 m). TN1 prints the
  // translations of ETRF89…ETRF2000 in centimetres; they are in millimetres
  // here like every other row.
  const std::string tn1 = "EUREF TN1 (Altamimi), ITRF to ETRF";
  const struct {
    const char* from;
    double epoch;
    IersRow row;
  } kEuref[] = {
      {"ITRF89", 1989.0, {"ETRF89", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.11, 0.57, -0.71, 0.0, "EPSG:7932"}},
      {"ITRF90", 1989.0, {"ETRF90", 19.0, 28.0, -23.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.11, 0.57, -0.71, 0.0, "EPSG:7933"}},
      {"ITRF91", 1989.0, {"ETRF91", 21.0, 25.0, -37.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.21, 0.52, -0.68, 0.0, "EPSG:7934"}},
      {"ITRF92", 1989.0, {"ETRF92", 38.0, 40.0, -37.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.21, 0.52, -0.68, 0.0, "EPSG:7935"}},
      {"ITRF93", 1989.0, {"ETRF93", 19.0, 53.0, -21.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.32, 0.78, -0.67, 0.0, "EPSG:7936"}},
      {"ITRF94", 1989.0, {"ETRF94", 41.0, 41.0, -49.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.20, 0.50, -0.65, 0.0, "EPSG:7937"}},
      {"ITRF96", 1989.0, {"ETRF96", 41.0, 41.0, -49.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.20, 0.50, -0.65, 0.0, "EPSG:7938"}},
      {"ITRF97", 1989.0, {"ETRF97", 41.0, 41.0, -49.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.20, 0.50, -0.65, 0.0, "EPSG:7939"}},
      {"ITRF2000", 1989.0, {"ETRF2000", 54.0, 51.0, -48.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.081, 0.490, -0.792, 0.0, "EPSG:7940"}},
      {"ITRF2005", 1989.0, {"ETRF2005", 56.0, 48.0, -37.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.054, 0.518, -0.781, 0.0, "EPSG:5900"}},
      {"ITRF2014", 1989.0, {"ETRF2014", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.085, 0.531, -0.770, 0.0, "EPSG:8366"}},
      // ETRF2000 from ITRF2005, ITRF2008 and ITRF2014 (TN1's tables for ETRF2000).
      {"ITRF2005", 2000.0, {"ETRF2000", 54.1, 50.2, -53.8, 0.40, 0.891, 5.390, -8.712, -0.2, 0.1, -1.8, 0.08, 0.081, 0.490, -0.792, 0.0, "EPSG:7950"}},
      {"ITRF2008", 2000.0, {"ETRF2000", 52.1, 49.3, -58.5, 1.34, 0.891, 5.390, -8.712, 0.1, 0.1, -1.8, 0.08, 0.081, 0.490, -0.792, 0.0, "EPSG:7951"}},
      {"ITRF2014", 2010.0, {"ETRF2000", 54.7, 52.2, -74.1, 2.12, 1.701, 10.290, -16.632, 0.1, 0.1, -1.9, 0.11, 0.081, 0.490, -0.792, 0.0, "EPSG:8405"}},
  };
  for (const auto& e : kEuref) {
    out.push_back(from_iers(e.from, e.epoch, e.row, tn1 + " (" + e.from + " to " + e.row.to + ")", false));
  }
  // ETRF2020 (TN1, 2023 edition): ITRF2020 turned by stable Eurasia's rotation
  // since 1989.0. Not in PROJ 9.1.1's EPSG v10.076; EPSG:10574 (ITRF2014 to
  // ETRF2020) is this set composed with ITRF2014 to ITRF2020.
  out.push_back(from_iers("ITRF2020", 1989.0,
                          {"ETRF2020", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.086, 0.519, -0.753, 0.0, ""},
                          tn1 + " (ITRF2020 to ETRF2020, 2023 edition)", false));
}

// The national frames and WGS 84's realizations.
void add_national_and_wgs84_sets(std::vector<CatalogTransformation>& out) {
  // National and WGS 84 frames, each as its producer publishes it. Rows are
  // in the position-vector convention, mm, mas and ppb; where the source
  // (and EPSG) uses the coordinate-frame convention the rotations and their
  // rates are negated here, and the row says so. EPSG states 0 m for the
  // defining sets.
  const struct {
    const char* from;
    double epoch;
    IersRow row;
    const char* source;
  } kNational[] = {
      // NGS: Pearson & Snay (2013), "Introducing HTDP 3.1 to transform coordinates across time and spatial reference
      // frames", GPS Solutions 17(1) (coordinate frame; rotations negated).
      {"ITRF2008", 1997.0,
       {"NAD83(2011)", 993.43, -1903.31, -526.55, 1.71504, -25.91467, -9.42645, -11.59935, 0.79, -0.60, -1.34, -0.10201,
        -0.06667, 0.75744, 0.05133, 0.0, "EPSG:7807"},
       "NGS, Pearson & Snay (2013), GPS Solutions 17, ITRF2008 to NAD83(2011) (coordinate frame, rotations negated)"},
      // NGS, ITRF2014 to NAD83(2011) as HTDP applies it (coordinate frame; rotations negated), to
      // HTDP's digits (htdp.f 3.6.0: ITRF94 -> NAD83(2011) less ITRF94 -> ITRF2014), as EPSG:8970
      // now gives them; PROJ 9.1.1's database rounds them (tz -0.5416 m, dtz -1.4 mm/yr: 0.45 mm
      // in ten years).
      {"ITRF2014", 2010.0,
       {"NAD83(2011)", 1005.30, -1909.21, -541.57, 0.36891, -26.78138, 0.42027, -10.93206, 0.79, -0.60, -1.44, -0.07201,
        -0.06667, 0.75744, 0.05133, 0.0, "EPSG:8970"},
       "NGS (HTDP), ITRF2014 to NAD83(2011) (coordinate frame, rotations negated)"},
      // NGS, HTDP user guide (v3.5 and later), table 5: ITRF2020 to NAD83(2011)
      // (coordinate frame; rotations negated); EPSG:10334, newer than PROJ
      // 9.1.1's database. The same numbers as NRCan's CSRS v8 set below.
      {"ITRF2020", 2010.0,
       {"NAD83(2011)", 1003.90, -1909.61, -541.17, -0.05109, -26.78138, 0.42027, -10.93206, 0.79, -0.70, -1.24, -0.07201,
        -0.06667, 0.75744, 0.05133, 0.0, ""},
       "NGS, HTDP user guide table 5, ITRF2020 to NAD83(2011) = EPSG:10334 (coordinate frame, rotations negated)"},
      // NRCan: the NGS sets in the position-vector convention, for NAD83(CSRS) v6 and v7.
      {"ITRF2008", 1997.0,
       {"NAD83(CSRSv6)", 993.43, -1903.31, -526.55, 1.71504, -25.91467, -9.42645, -11.59935, 0.79, -0.60, -1.34, -0.102,
        -0.06667, 0.75744, 0.05133, 0.0, "EPSG:8264"},
       "NRCan, NAD83(CSRS) v6 from ITRF2008"},
      {"ITRF2014", 2010.0,
       {"NAD83(CSRSv7)", 1005.3, -1909.2, -541.6, 0.37, -26.7814, 0.4203, -10.9321, 0.8, -0.6, -1.4, -0.07, -0.0667, 0.7574,
        0.0513, 0.0, "EPSG:8265"},
       "NRCan, NAD83(CSRS) v7 from ITRF2014"},
      // NRCan: NAD83(CSRS) v8 from ITRF2020 (2022), as TRX applies it: the v7
      // set composed with the IERS ITRF2020 → ITRF2014 set (T and D at 2010.0
      // shifted by it, rates likewise). Newer than PROJ 9.1.1's database.
      {"ITRF2020", 2010.0,
       {"NAD83(CSRSv8)", 1003.90, -1909.61, -541.17, -0.05109, -26.78138, 0.42027, -10.93206, 0.79, -0.70, -1.24, -0.07201,
        -0.06667, 0.75744, 0.05133, 0.0, ""},
       "NRCan, NAD83(CSRS) v8 from ITRF2020 (v7 composed with ITRF2020 to ITRF2014)"},
      // ICSM, GDA2020 Technical Manual (v1.x), GDA94 to GDA2020 (7 parameters, coordinate frame; rotations negated)
      // and ITRF2014 to GDA2020 (the Australian plate's rotation since 2020.0, coordinate frame; rates negated).
      {"GDA94", 2020.0,
       {"GDA2020", 61.55, -10.87, -40.19, -9.994, 39.4924, 32.7221, 32.8979, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.01,
        "EPSG:8048"},
       "ICSM, GDA2020 Technical Manual, GDA94 to GDA2020 (coordinate frame, rotations negated)"},
      {"ITRF2014", 2020.0,
       {"GDA2020", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.50379, -1.18346, -1.20716, 0.03, "EPSG:8049"},
       "ICSM, GDA2020 Technical Manual, ITRF2014 to GDA2020 (coordinate frame, rates negated)"},
      // WGS 84 realizations (NGA), tied to their ITRF as EPSG records them, and NGA's sets between realizations
      // (coordinate frame; rotations negated).
      {"WGS84(G730)", 2000.0, {"ITRF92", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.2, "EPSG:7672"}, "NGA/EPSG, WGS 84 (G730) aligned with ITRF92"},
      {"WGS84(G873)", 2000.0, {"ITRF94", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.1, "EPSG:9076"}, "NGA/EPSG, WGS 84 (G873) aligned with ITRF94"},
      {"WGS84(G1150)", 2000.0, {"ITRF2000", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.02, "EPSG:7670"}, "NGA/EPSG, WGS 84 (G1150) aligned with ITRF2000"},
      {"WGS84(G1674)", 2000.0, {"ITRF2008", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.01, "EPSG:7669"}, "NGA/EPSG, WGS 84 (G1674) aligned with ITRF2008"},
      {"WGS84(G1762)", 2000.0, {"ITRF2008", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.01, "EPSG:7666"}, "NGA/EPSG, WGS 84 (G1762) aligned with ITRF2008"},
      {"WGS84(G2139)", 2000.0, {"ITRF2014", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.01, "EPSG:9757"}, "NGA/EPSG, WGS 84 (G2139) aligned with ITRF2014"},
      // NGA Office of Geomatics press release NGA-U-2023-02846 (2024-01-02):
      // WGS 84 (G2296), in use from 2024-01-07 (GPS week 2296), is aligned
      // with ITRF2020 (through IGS20); EPSG CRS 10604. NGA gives no separate
      // accuracy for the tie: that of G2139 to ITRF2014 (EPSG:9757) is used.
      // The operation is newer than PROJ 9.1.1's EPSG database.
      {"WGS84(G2296)", 2000.0, {"ITRF2020", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.01, ""}, "NGA, WGS 84 (G2296) aligned with ITRF2020 (press release NGA-U-2023-02846)"},
      {"WGS84(G730)", 2000.0, {"WGS84(G873)", -20.0, -16.0, 14.0, -0.69, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.04, "EPSG:9961"},
       "NGA, WGS 84 (G730) to (G873)"},
      {"WGS84(G873)", 2005.0, {"WGS84(G1150)", 1.1, -4.7, 22.0, 1.45, 0.0, 0.0, -0.16, 0.0, 0.6, 1.4, -0.01, 0.0, 0.0, -0.02, 0.03, "EPSG:9962"},
       "NGA, WGS 84 (G873) to (G1150) (coordinate frame, rotations negated)"},
      {"WGS84(G1150)", 2005.0, {"WGS84(G1674)", -2.4, 1.6, 23.2, 2.08, 0.27, -0.27, 0.38, -0.1, -0.1, 1.8, -0.08, 0.0, 0.0, 0.0, 0.02, "EPSG:9963"},
       "NGA, WGS 84 (G1150) to (G1674) (coordinate frame, rotations negated)"},
      {"WGS84(G1674)", 2000.0, {"WGS84(G1762)", -4.0, 3.0, 4.0, -6.9, -0.27, 0.27, -0.38, 0, 0, 0, 0, 0, 0, 0, 0.01, "EPSG:7667"},
       "NGA, WGS 84 (G1674) to (G1762) (coordinate frame, rotations negated)"},
      {"WGS84(G1150)", 2000.0, {"WGS84(G1762)", -6.0, 5.0, 20.0, -4.5, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.02, "EPSG:7668"},
       "NGA, WGS 84 (G1150) to (G1762) (coordinate frame)"},
      {"WGS84(G1762)", 2000.0, {"WGS84(G2139)", 5.8, -6.4, 7.0, -4.4, -0.08, -0.04, -0.12, 0, 0, 0, 0, 0, 0, 0, 0.01, "EPSG:9756"},
       "NGA, WGS 84 (G1762) to (G2139) (coordinate frame, rotations negated)"},
  };
  for (const auto& n : kNational) out.push_back(from_iers(n.from, n.epoch, n.row, n.source, false));
}

std::vector<CatalogTransformation> build_catalog() {
  std::vector<CatalogTransformation> out;
  add_itrf_sets(out);
  add_etrf_sets(out);
  add_national_and_wgs84_sets(out);
  return out;
}

#undef ITRF2020_OLD_RATES
#undef ITRF2014_OLD_RATES
#undef ITRF2008_OLD_RATES

std::vector<PlateMotionModel> build_plate_models() {
  // Altamimi, Métivier, Rebischung, Rouby, Collilieux (2017), "ITRF2014 plate
  // motion model", Geophys. J. Int. 209(3), 1906–1912, doi:10.1093/gji/ggx136,
  // Table 1 (ω in mas/yr, ITRF2014).
  const std::string src = "Altamimi et al. (2017), ITRF2014 plate motion model, GJI 209, doi:10.1093/gji/ggx136, Table 1";
  // Table 1 also gives the WRMS of each plate's residual velocities, east
  // and north (mm/yr).
  const struct {
    const char* plate;
    double wx, wy, wz, wrms_e, wrms_n;
  } kItrf2014[] = {
      {"ANTA", -0.248, -0.324, 0.675, 0.20, 0.16}, {"ARAB", 1.154, -0.136, 1.444, 0.36, 0.43},
      {"AUST", 1.510, 1.182, 1.215, 0.24, 0.20},   {"EURA", -0.085, -0.531, 0.770, 0.23, 0.19},
      {"INDI", 1.154, -0.005, 1.454, 0.21, 0.21},  {"NAZC", -0.333, -1.544, 1.623, 0.13, 0.19},
      {"NOAM", 0.024, -0.694, -0.063, 0.23, 0.28}, {"NUBI", 0.099, -0.614, 0.733, 0.28, 0.36},
      {"PCFC", -0.409, 1.047, -2.169, 0.36, 0.31}, {"SOAM", -0.270, -0.301, -0.140, 0.34, 0.35},
      {"SOMA", -0.121, -0.794, 0.884, 0.32, 0.30},
  };
  std::vector<PlateMotionModel> out;
  for (const auto& p : kItrf2014) {
    out.push_back({"ITRF2014", p.plate, Eigen::Vector3d(p.wx, p.wy, p.wz), Eigen::Vector3d::Zero(), src, p.wrms_e,
                   p.wrms_n, "Table 1 of the same paper"});
  }
  // Altamimi, Métivier, Rebischung, Collilieux, Chanard, Barnéoud (2023),
  // "ITRF2020 plate motion model", Geophys. Res. Lett. 50, e2023GL106373,
  // doi:10.1029/2023GL106373: Table 1 (ω in mas/yr) and Table 2 (origin rate
  // bias 0.37, 0.35, 0.74 mm/yr).
  const std::string src2020 =
      "Altamimi et al. (2023), ITRF2020 plate motion model, GRL 50, doi:10.1029/2023GL106373, Tables 1 and 2";
  const struct {
    const char* plate;
    double wx, wy, wz;
  } kItrf2020[] = {
      {"AMUR", -0.131, -0.551, 0.837}, {"ANTA", -0.269, -0.312, 0.678}, {"ARAB", 1.129, -0.146, 1.438},
      {"AUST", 1.487, 1.175, 1.223},   {"CARB", 0.207, -1.422, 0.726},  {"EURA", -0.085, -0.519, 0.753},
      {"INDI", 1.137, 0.013, 1.444},   {"NAZC", -0.327, -1.561, 1.605}, {"NOAM", 0.045, -0.666, -0.098},
      {"NUBI", 0.090, -0.585, 0.717},  {"PCFC", -0.404, 1.021, -2.154}, {"SOAM", -0.261, -0.282, -0.157},
      {"SOMA", -0.081, -0.719, 0.864},
  };
  const Eigen::Vector3d orb_2020 = 1e-3 * Eigen::Vector3d(0.37, 0.35, 0.74);
  // The paper states the model's overall precision, 0.25 mm/yr WRMS of the
  // 518 sites' residual velocities (abstract and key points); it is used for
  // every plate and both components.
  constexpr double kWrms2020_mm_per_year = 0.25;
  for (const auto& p : kItrf2020) {
    out.push_back({"ITRF2020", p.plate, Eigen::Vector3d(p.wx, p.wy, p.wz), orb_2020, src2020, kWrms2020_mm_per_year,
                   kWrms2020_mm_per_year, "the paper's overall precision, for every plate"});
  }
  return out;
}

}  // namespace

double PlateMotionModel::motion_uncertainty_m(double years) const {
  return std::hypot(wrms_east_mm_per_year, wrms_north_mm_per_year) * 1e-3 * std::abs(years);
}

Eigen::Vector3d PlateMotionModel::velocity_m_per_year(const EcefPosition& x) const {
  const Eigen::Vector3d w_rad = omega_mas_per_year * (Angle::milliarcseconds(1.0).rad());
  Eigen::Vector3d v = w_rad.cross(x.m);
  if (!origin_rate_bias_m_per_year.isZero(0.0)) {
    // The bias's horizontal part: its component along the ellipsoidal
    // normal (GRS80) removed.
    static const GeocentricConverter grs80(Ellipsoid::grs80());
    const GeodeticPosition g = grs80.geodetic_from_ecef(x);
    const double cl = std::cos(g.lat.rad()), sl = std::sin(g.lat.rad());
    const Eigen::Vector3d up(cl * std::cos(g.lon.rad()), cl * std::sin(g.lon.rad()), sl);
    v += origin_rate_bias_m_per_year - origin_rate_bias_m_per_year.dot(up) * up;
  }
  return v;
}

const std::vector<CatalogTransformation>& catalog_transformations() {
  static const std::vector<CatalogTransformation> kCatalog = build_catalog();
  return kCatalog;
}

const std::vector<PlateMotionModel>& plate_motion_models() {
  static const std::vector<PlateMotionModel> kModels = build_plate_models();
  return kModels;
}

std::optional<PlateMotionModel> find_plate_motion_model(std::string_view frame, std::string_view plate) {
  for (const auto& m : plate_motion_models()) {
    if (m.frame == frame && m.plate == plate) return m;
  }
  return std::nullopt;
}

EcefPosition FramePathStep::apply(const EcefPosition& x, DecimalYear t) const {
  const AffineMap m = target_from_source(evaluate_at(edge->params, t), RotationModel::small_angle);
  return EcefPosition(reverse ? m.inverse().apply(x.m) : m.apply(x.m));
}

bool CatalogTransformation::time_dependent() const {
  const auto& r = params.rates;
  return !r.dt_m_per_year.isZero(0.0) || r.drx_per_year.rad() != 0.0 || r.dry_per_year.rad() != 0.0 ||
         r.drz_per_year.rad() != 0.0 || r.dds_per_year.unitless() != 0.0;
}

bool FramePath::time_dependent() const {
  return std::any_of(steps.begin(), steps.end(), [](const FramePathStep& s) { return s.edge->time_dependent(); });
}

double FramePath::accuracy_m() const {
  double s = 0.0;
  for (const auto& st : steps) s += st.edge->accuracy_m * st.edge->accuracy_m;
  return std::sqrt(s);
}

AffineMap FramePath::at(DecimalYear t) const {
  AffineMap m = AffineMap::identity();
  for (const auto& st : steps) {
    const AffineMap step = target_from_source(evaluate_at(st.edge->params, t), RotationModel::small_angle);
    m = compose(st.reverse ? step.inverse() : step, m);
  }
  return m;
}

EcefPosition FramePath::apply(const EcefPosition& x, DecimalYear t) const {
  EcefPosition y = x;
  for (const auto& st : steps) y = st.apply(y, t);
  return y;
}

std::string FramePath::describe() const {
  std::string out;
  for (const auto& st : steps) {
    out += std::string(st.from()) + " → " + std::string(st.to());
    if (st.reverse) out += " (reverse of " + st.edge->from + " → " + st.edge->to + ")";
    out += ", ±" + format_shortest(st.edge->accuracy_m) + " m: " + st.edge->source;
    if (!st.edge->epsg.empty()) out += " = " + st.edge->epsg + (st.edge->epsg_reversed ? " reversed" : "");
    out += "\n";
  }
  if (steps.empty()) out = from + " = " + to + ": no transformation\n";
  return out;
}

FrameEpochTransform::FrameEpochTransform(FramePath path, DecimalYear t_from, DecimalYear t_to, const PlateMotionModel* plate,
                                         std::string_view where)
    : path_(std::move(path)),
      t_from_(t_from),
      t_to_(t_to),
      at_from_(path_.at(t_from)),
      // A central difference over a year gives the velocity through the
      // path: the parameters are linear in time and a point's velocity is
      // constant, so it is exact to terms of order ṡ·v·(1 yr) (1e-12 m/yr).
      ahead_(path_.at(DecimalYear{t_from.year + 1.0})),
      behind_(path_.at(DecimalYear{t_from.year - 1.0})),
      plate_(plate) {
  if (plate_ && t_to.year != t_from.year) {
    to_plate_frame_ = find_frame_path(path_.from, plate_->frame, where).at(t_from);
    from_plate_frame_ = find_frame_path(plate_->frame, path_.to, where).at(t_to);
  }
}

StateVector FrameEpochTransform::apply(const StateVector& in, std::string_view where) const {
  const double dt = t_to_.year - t_from_.year;
  if (in.v_m_per_year) {
    const Eigen::Vector3d& v = *in.v_m_per_year;
    const Eigen::Vector3d v_to = (ahead_.apply(in.x.m + v) - behind_.apply(in.x.m - v)) / 2.0;
    return {EcefPosition(Eigen::Vector3d(at_from_.apply(in.x.m) + v_to * dt)), v_to};
  }
  if (dt == 0.0) return {EcefPosition(at_from_.apply(in.x.m)), std::nullopt};
  if (!to_plate_frame_) {
    throw Error(ErrorKind::input, "E_EPOCH_PROPAGATION",
                std::string(where) + ": moving coordinates from " + format_decimal_year(t_from_) + " to " +
                    format_decimal_year(t_to_) +
                    " needs velocities (columns vx_m_per_year, vy_m_per_year, vz_m_per_year) or a plate motion model "
                    "(--plate, e.g. EURA)");
  }
  EcefPosition hub(to_plate_frame_->apply(in.x.m));
  hub.m += plate_->velocity_m_per_year(hub) * dt;
  return {EcefPosition(from_plate_frame_->apply(hub.m)), std::nullopt};
}

std::vector<std::string> catalog_frame_names() {
  std::set<std::string> names;
  for (const auto& c : catalog_transformations()) {
    names.insert(c.from);
    names.insert(c.to);
  }
  return {names.begin(), names.end()};
}

FramePath find_frame_path(std::string_view from, std::string_view to, std::string_view where) {
  const auto names = catalog_frame_names();
  const auto known = [&](std::string_view n) { return std::find(names.begin(), names.end(), n) != names.end(); };
  for (std::string_view n : {from, to}) {
    if (!known(n)) {
      std::string list;
      for (const auto& k : names) list += (list.empty() ? "" : ", ") + k;
      throw Error(ErrorKind::input, "E_FRAME_UNKNOWN",
                  std::string(where) + ": frame " + std::string(n) + " is not in geoanchor's catalog; it knows " + list);
    }
  }
  FramePath path{std::string(from), std::string(to), {}};
  if (from == to) return path;
  // Breadth-first over frames: fewest steps; among equally short paths the
  // smaller sum of squared accuracies wins.
  struct Best {
    int steps = -1;
    double acc2 = 0.0;
    std::vector<FramePathStep> path;
  };
  std::map<std::string, Best, std::less<>> best;
  best[std::string(from)] = {0, 0.0, {}};
  std::deque<std::string> queue{std::string(from)};
  while (!queue.empty()) {
    const std::string here = queue.front();
    queue.pop_front();
    const Best current = best[here];
    for (const auto& e : catalog_transformations()) {
      for (bool reverse : {false, true}) {
        const std::string& a = reverse ? e.to : e.from;
        const std::string& b = reverse ? e.from : e.to;
        if (a != here) continue;
        Best next{current.steps + 1, current.acc2 + e.accuracy_m * e.accuracy_m, current.path};
        next.path.push_back({&e, reverse});
        auto it = best.find(b);
        if (it == best.end()) {
          best[b] = next;
          queue.push_back(b);
        } else if (it->second.steps == next.steps && next.acc2 < it->second.acc2) {
          it->second = next;
        }
      }
    }
  }
  const auto it = best.find(to);
  if (it == best.end()) {
    throw Error(ErrorKind::input, "E_FRAME_NO_PATH",
                std::string(where) + ": no published transformation connects " + std::string(from) + " and " + std::string(to));
  }
  path.steps = it->second.path;
  return path;
}

}  // namespace geoanchor::geodesy
