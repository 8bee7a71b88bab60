#include "geoanchor/workflow/fit_checks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/frame.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/geodesy/projection.hpp"
#include "geoanchor/geodesy/quantization.hpp"

namespace geoanchor::workflow {
namespace {

// A swap is named when the marks lie farther apart than any datum shift as
// read and closer than this once one frame is read the other way round.
constexpr double kFarApart_m = 100e3;
constexpr double kSwappedClose_m = 1e3;

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

std::vector<std::string> control_set_warnings(const geodesy::ControlSet& set) {
  std::vector<std::string> out;
  for (const auto* f : {&set.source_frame, &set.target_frame}) {
    if (!*f) continue;
    if (auto w = geodesy::ensemble_warning(**f)) out.push_back(std::move(*w));
  }
  for (const bool source : {true, false}) {
    const geodesy::ControlInputForm& form = source ? set.source_input : set.target_input;
    for (const auto& w : form.crs_warnings) out.push_back(std::string(source ? "source" : "target") + " CRS: " + w);
    if (form.form != geodesy::CoordinateForm::ecef || set.points.size() < 3) continue;
    bool all = true;
    double widest = 0.0;
    for (const auto& p : set.points) {
      const Eigen::Vector3d& v = source ? p.source_as_read : p.target_as_read;
      for (int c = 0; c < 3; ++c) {
        all = all && geodesy::is_float32_valued(v(c));
        const double q = geodesy::float32_spacing(v(c));
        if (!(q <= widest)) widest = q;
      }
      if (!all) break;
    }
    if (all) {
      out.push_back(std::string(source ? "source" : "target") +
                    " ECEF coordinates: every value in " + set.source_name +
                    " is a float32 value (or integer metres): they were stored in single precision, quantized in steps "
                    "of up to " + format_fixed(widest, 3) +
                    " m; residuals of that size are quantization, not blunders, and no fit to them is better than that. "
                    "Export the coordinates in double precision");
    }
  }
  // Grid coordinates on a forced UTM zone: marks beyond the zone's band plus
  // its margin are warned as convert warns a forced zone (issue 12 point 1);
  // the reader already refused those where the projection loses accuracy.
  for (const bool source : {true, false}) {
    const geodesy::ControlInputForm& form = source ? set.source_input : set.target_input;
    if (form.form != geodesy::CoordinateForm::projected || !form.projection || !form.projection->utm) continue;
    const geodesy::UtmZone& zone = *form.projection->utm;
    const geodesy::GeocentricConverter conv(form.projection->ellipsoid);
    std::size_t outside = 0;
    const geodesy::ControlPoint* worst = nullptr;
    double worst_deg = 0.0;
    for (const auto& p : set.points) {
      const geodesy::GeodeticPosition g = conv.geodetic_from_ecef(source ? p.source : p.target);
      const geodesy::UtmBandCheck c = geodesy::utm_band_check(zone, g);
      if (!geodesy::outside_band_margin(c)) continue;
      ++outside;
      const double excess = c.band_exists ? c.excess.deg() : std::numeric_limits<double>::infinity();
      if (!worst || excess > worst_deg) {
        worst = &p;
        worst_deg = excess;
      }
    }
    if (outside == 0) continue;
    const geodesy::GeodeticPosition g = conv.geodetic_from_ecef(source ? worst->source : worst->target);
    out.push_back(std::string(source ? "source" : "target") + " grid coordinates on UTM zone " + zone.to_string() + ": " +
                  std::to_string(outside) + " of " + std::to_string(set.points.size()) +
                  " marks lie beyond the zone's band (" + geodesy::utm_band_text(zone, g.lat) + ") by more than " +
                  format_shortest(geodesy::kUtmBandMargin.deg()) + "°" +
                  (std::isfinite(worst_deg) ? ", the farthest " + worst->id + " by " + format_fixed(worst_deg, 2) + "°"
                                            : ", e.g. " + worst->id) +
                  ": is the zone right? Grid scale and convergence grow fast away from the central meridian");
  }
  return out;
}

std::optional<std::string> likely_lat_lon_swap(const geodesy::ControlSet& set) {
  if (set.source_input.form != geodesy::CoordinateForm::geodetic || set.target_input.form != geodesy::CoordinateForm::geodetic ||
      set.points.empty()) {
    return std::nullopt;
  }
  const geodesy::GeocentricConverter src_conv(set.source_input.ellipsoid), dst_conv(set.target_input.ellipsoid);
  auto swapped = [&](const Eigen::Vector3d& as_read, bool source) -> std::optional<geodesy::EcefPosition> {
    if (!(std::fabs(as_read.y()) <= 90.0)) return std::nullopt;
    return (source ? src_conv : dst_conv).ecef_from_geodetic({geodesy::Angle::degrees(as_read.y()), geodesy::Angle::degrees(as_read.x()),
                                    geodesy::EllipsoidalHeight{as_read.z()}});
  };
  std::vector<double> as_read, src_swapped, dst_swapped;
  for (const auto& p : set.points) {
    as_read.push_back((p.target.m - p.source.m).norm());
    const auto s = swapped(p.source_as_read, true), t = swapped(p.target_as_read, false);
    src_swapped.push_back(s ? (p.target.m - s->m).norm() : std::numeric_limits<double>::infinity());
    dst_swapped.push_back(t ? (t->m - p.source.m).norm() : std::numeric_limits<double>::infinity());
  }
  const double apart = median(as_read);
  if (!(apart > kFarApart_m)) return std::nullopt;
  // Read either frame the other way round and the frames agree alike when
  // both swapped readings are positions on the Earth: the data cannot tell
  // which header is wrong, so the message names both.
  const double close_src = median(src_swapped), close_dst = median(dst_swapped);
  if (close_src < kSwappedClose_m && close_dst < kSwappedClose_m) {
    return set.source_name + ": the marks lie " + format_fixed(apart / 1e3, 1) + " km apart between the frames (median), but " +
           format_fixed(std::min(close_src, close_dst), 3) +
           " m apart when one frame's latitude and longitude are read the other way round: the columns lat_src_deg/lon_src_deg "
           "or lat_dst_deg/lon_dst_deg look swapped (the data cannot tell which); check both headers against the data";
  }
  for (const bool source : {true, false}) {
    const double close = median(source ? src_swapped : dst_swapped);
    if (close < kSwappedClose_m) {
      const std::string role = source ? "src" : "dst";
      return set.source_name + ": the marks lie " + format_fixed(apart / 1e3, 1) +
             " km apart between the frames (median), but " + format_fixed(close, 3) + " m apart when lat_" + role +
             "_deg and lon_" + role + "_deg are read the other way round: the " + (source ? "source" : "target") +
             " latitude and longitude columns look swapped; check the header against the data";
    }
  }
  return std::nullopt;
}

std::optional<geodesy::DecimalYear> fixed_fit_epoch(const geodesy::ControlSet& set, solver::FitModel model) {
  if (model == solver::FitModel::helmert14) return std::nullopt;  // carries its own epochs
  const auto undated_dynamic = [](const std::optional<geodesy::Frame>& f) {
    return f && geodesy::is_dynamic(*f) && !f->epoch();
  };
  if (!undated_dynamic(set.source_frame) && !undated_dynamic(set.target_frame)) return std::nullopt;
  const geodesy::ControlPoint* earliest = nullptr;
  const geodesy::ControlPoint* latest = nullptr;
  double sum = 0.0;
  std::size_t used = 0;
  for (const auto& p : set.points) {
    if (!p.epoch) return std::nullopt;  // the reader refused this set; nothing to name
    if (!p.use) continue;  // the epoch is the fitted marks'; a mark set aside does not shift it
    if (!earliest || p.epoch->year < earliest->epoch->year) earliest = &p;
    if (!latest || p.epoch->year > latest->epoch->year) latest = &p;
    sum += p.epoch->year;
    ++used;
  }
  if (!earliest) return std::nullopt;
  const double spread = latest->epoch->year - earliest->epoch->year;
  if (!(spread <= kCampaignSpread_yr)) {
    const auto& f = undated_dynamic(set.source_frame) ? *set.source_frame : *set.target_frame;
    throw Error(ErrorKind::input, "E_EPOCH_SPREAD",
                set.source_name + ": the points' epochs span " + format_fixed(spread, 3) + " years (mark " + earliest->id +
                    " at " + format_fixed(earliest->epoch->year, 3) + ", mark " + latest->id + " at " +
                    format_fixed(latest->epoch->year, 3) + ") in the dynamic frame " + f.name() + ", more than " +
                    format_shortest(kCampaignSpread_yr) + " year: a transform of fixed parameters holds at one epoch; " +
                    "fit --model helmert14, or give the coordinates at one epoch (the frame as " + f.name() + "@YYYY.Y)");
  }
  return geodesy::DecimalYear{sum / static_cast<double>(used)};
}

std::optional<geodesy::Frame> written_frame(const std::optional<geodesy::Frame>& frame, const geodesy::ControlSet& set,
                                            solver::FitModel model) {
  if (!frame || !geodesy::is_dynamic(*frame) || frame->epoch()) return frame;
  const auto epoch = fixed_fit_epoch(set, model);
  if (!epoch) return frame;
  return geodesy::Frame::parse(frame->name() + "@" + format_fixed(epoch->year, 3), "the points' mean epoch");
}

std::optional<std::string> far_apart_mark(const geodesy::ControlSet& set) {
  // Only the marks the fit uses: a mark set aside (use = 0) does not stop it.
  std::vector<const geodesy::ControlPoint*> used;
  for (const auto& p : set.points) {
    if (p.use) used.push_back(&p);
  }
  if (used.size() < 2) return std::nullopt;
  std::vector<double> apart;
  for (const auto* p : used) apart.push_back((p->target.m - p->source.m).norm());
  const double typical = median(apart);
  if (!(typical <= kFarApart_m)) return std::nullopt;  // the whole set disagrees: likely_lat_lon_swap's case
  std::size_t count = 0;
  const geodesy::ControlPoint* first = nullptr;
  double first_apart = 0.0;
  for (std::size_t i = 0; i < used.size(); ++i) {
    if (apart[i] <= kFarApart_m) continue;  // NaN cannot occur: positions are checked on the Earth
    if (count++ == 0) first = used[i], first_apart = apart[i];
  }
  if (!first) return std::nullopt;
  // The role that is out of place: the one farther from the other marks'
  // positions in its own frame (their component-wise median).
  const auto distance_from_others = [&](bool source) {
    Eigen::Vector3d m;
    for (int c = 0; c < 3; ++c) {
      std::vector<double> v;
      for (const auto* p : used) v.push_back((source ? p->source.m : p->target.m)(c));
      m(c) = median(v);
    }
    return ((source ? first->source.m : first->target.m) - m).norm();
  };
  const bool source_out = distance_from_others(true) > distance_from_others(false);
  // Whether that role reads close to the other with its latitude and longitude swapped.
  std::string why = "in the " + std::string(source_out ? "source" : "target") +
                    " columns, which lie far from the other marks: latitude and longitude swapped, or a wrong unit?";
  for (const bool source : {source_out}) {
    const geodesy::ControlInputForm& form = source ? set.source_input : set.target_input;
    if (form.form != geodesy::CoordinateForm::geodetic) continue;
    const Eigen::Vector3d& as_read = source ? first->source_as_read : first->target_as_read;
    if (!(std::fabs(as_read.y()) <= 90.0)) continue;
    const geodesy::EcefPosition swapped = geodesy::GeocentricConverter(form.ellipsoid)
                                              .ecef_from_geodetic({geodesy::Angle::degrees(as_read.y()), geodesy::Angle::degrees(as_read.x()),
                                                                   geodesy::EllipsoidalHeight{as_read.z()}});
    const double close = ((source ? first->target.m : first->source.m) - swapped.m).norm();
    if (close < kSwappedClose_m) {
      why = "read with its " + std::string(source ? "source" : "target") + " latitude and longitude the other way round, they lie " +
            format_fixed(close, 3) + " m apart: those two cells look swapped in this row.";
      break;
    }
  }
  return set.source_name + (first->line ? ":" + std::to_string(first->line) : std::string()) + ": mark " + first->id +
         ": its source and target lie " + format_fixed(first_apart / 1e3, 1) + " km apart, the marks' median " +
         format_fixed(typical, 3) + " m" + (count > 1 ? " (" + std::to_string(count) + " marks are that far apart)" : "") +
         "; " + why + " Nothing was fitted";
}

std::optional<std::string> orthometric_height_warning(const solver::FitResult& r, const geodesy::ControlSet& set,
                                                      const geodesy::GeoidGrid& geoid) {
  if (r.model == solver::FitModel::enu_origin || r.model == solver::FitModel::site_calibration) return std::nullopt;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (std::size_t i = 0; i < r.points.size() && i < set.points.size(); ++i) {
    if (!r.points[i].used) continue;
    sum += set.points[i].source.m;
    ++n;
  }
  if (n == 0) return std::nullopt;
  const geodesy::EcefPosition centroid(Eigen::Vector3d(sum / static_cast<double>(n)));
  const std::optional<geodesy::DecimalYear> epoch =
      r.model == solver::FitModel::helmert14 ? r.reference_epoch : std::optional<geodesy::DecimalYear>{};
  if (r.model == solver::FitModel::helmert14 && !epoch) return std::nullopt;
  const geodesy::GeocentricConverter geocentric(set.source_input.ellipsoid);  // at the source centroid
  const auto [n_m, up] = geodesy::geoid_along_up(geoid, geocentric, centroid);
  const double offset_m = (solver::apply_fit(r, centroid, epoch).m - centroid.m).dot(up);
  if (!std::isfinite(n_m) || !std::isfinite(offset_m) || !(std::fabs(offset_m) > kHeightTypeMinOffset_m)) return std::nullopt;
  const double tolerance_m = std::max(kHeightTypeTolerance_m, kHeightTypeTolerance * std::fabs(n_m));
  for (const bool source : {true, false}) {
    // Source heights H = h − N put the source N too low: target − source = +N.
    const double expected_m = source ? n_m : -n_m;
    const double off_m = std::fabs(offset_m - expected_m);
    if (!(off_m < tolerance_m)) continue;
    return "the transform's vertical offset " + format_fixed(offset_m, 3) + " m is within " + format_fixed(off_m, 3) +
           " m of the " + geoid.model_name() + " undulation N = " + format_fixed(n_m, 3) +
           " m here: one frame's heights look orthometric (H = h − N), by its sign the " + (source ? "source" : "target") +
           "'s; give them as H_" + (source ? "src" : "dst") +
           "_m with --geoid EGM96, or ellipsoidal heights h (geoanchor diagnose tests this hypothesis)";
  }
  return std::nullopt;
}

std::optional<FitRefusal> fit_refusal(const solver::FitResult& r, const std::string& source_name,
                                      bool accept_failed_global_test) {
  if (!r.refused_because.empty()) {
    return FitRefusal{"E_FIT_SNOOPING_LIMIT", source_name + ": " + r.refused_because + "; no transform was written"};
  }
  const auto& g = r.global_test;
  if (g.failed_high() && !accept_failed_global_test) {
    // The flagged marks first, in the order data snooping would remove them.
    const std::vector<std::size_t> failing = solver::failing_marks(r);
    std::string flagged;
    constexpr std::size_t kNamed = 10;
    for (std::size_t k = 0; k < failing.size() && k < kNamed; ++k) {
      const solver::PointResult& p = r.points[failing[k]];
      flagged += (k ? ", " : "") + p.id + " (|w| " + format_fixed(p.w_max, 2) +
                 (p.snooping_rank > 0 ? ", snooping rank " + std::to_string(p.snooping_rank) : std::string()) + ")";
    }
    if (failing.size() > kNamed) flagged += " and " + std::to_string(failing.size() - kNamed) + " more";
    return FitRefusal{
        "E_FIT_GLOBAL_TEST",
        source_name + ": " +
            (failing.empty() ? std::string()
                             : std::to_string(failing.size()) + " mark" + (failing.size() == 1 ? " fails its" : "s fail their") +
                                   " point test: " + flagged + "; ") +
            "global test failed high (" + format_fixed(g.statistic, 2) + " > " + format_fixed(g.critical_upper, 2) +
            ", σ0 = " + (r.sigma0 ? format_fixed(*r.sigma0, 3) : std::string("undefined")) +
            "): the residuals do not fit the stated sigmas; no transform was written. hint: " +
            (failing.empty() ? "look for blunders (residual table), wrong sigmas, or a wrong model"
                             : "--remove-outliers removes the flagged marks in that order and fits again; else look for "
                               "wrong sigmas or a wrong model") +
            "; --accept-failed-global-test writes it anyway"};
  }
  return std::nullopt;
}

}  // namespace geoanchor::workflow
