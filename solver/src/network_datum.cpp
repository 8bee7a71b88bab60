// The datum of a network adjustment (network_datum.hpp).

#include "network_datum.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "datum_rank.hpp"
#include "fit_common.hpp"
#include "geoanchor/base/error.hpp"
#include "geoanchor/base/parallel.hpp"
#include "network_free_datum.hpp"

namespace geoanchor::solver {

using geodesy::NetworkSpace;

namespace {

// The motions of a station's position, per parameter (in the positions' axes).
struct Motion {
  std::string name;
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> move;
  Eigen::Vector3d rotation_axis = Eigen::Vector3d::Zero();  // for the orientations
};

// The datum parameters' motions in a network of this space and dimensions,
// about `centroid`, the rotations and scale per `radius` (datum_vectors).
std::vector<Motion> datum_motions(const geodesy::Network& net, const Eigen::Vector3d& centroid, double radius) {
  const bool ellipsoidal = net.space == NetworkSpace::ellipsoidal;
  std::vector<Motion> motions;
  const char* axis_names[] = {"X", "Y", "Z"};
  if (ellipsoidal) {
    for (int k = 0; k < 3; ++k) {
      motions.push_back({std::string("translation along ") + axis_names[k] + " (ECEF)",
                         [k](const Eigen::Vector3d&) { return Eigen::Vector3d::Unit(k); }, Eigen::Vector3d::Zero()});
    }
    for (int k = 0; k < 3; ++k) {
      motions.push_back({std::string("rotation about ") + axis_names[k] + " (ECEF, through the network's centroid)",
                         [k, centroid, radius](const Eigen::Vector3d& x) {
                           return Eigen::Vector3d(Eigen::Vector3d::Unit(k).cross(x - centroid) / radius);
                         },
                         Eigen::Vector3d::Unit(k) / radius});
    }
    motions.push_back({"scale", [centroid, radius](const Eigen::Vector3d& x) { return Eigen::Vector3d((x - centroid) / radius); },
                       Eigen::Vector3d::Zero()});
  } else {
    const char* local_names[] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      if (!estimated_component(net, k)) continue;
      motions.push_back({std::string("translation along ") + local_names[k],
                         [k](const Eigen::Vector3d&) { return Eigen::Vector3d::Unit(k); }, Eigen::Vector3d::Zero()});
    }
    if (net.local_dimensions == 3) {
      // A 3-D network turns about its horizontal axes too (slope distances
      // alone leave all three rotations free).
      for (int k = 0; k < 2; ++k) {
        motions.push_back({std::string("rotation about the ") + local_names[k] + " axis (through the network's centroid)",
                           [k, centroid, radius](const Eigen::Vector3d& x) {
                             return Eigen::Vector3d(Eigen::Vector3d::Unit(k).cross(x - centroid) / radius);
                           },
                           Eigen::Vector3d::Unit(k) / radius});
      }
    }
    if (net.local_dimensions >= 2) {
      motions.push_back({"rotation about the vertical",
                         [centroid, radius](const Eigen::Vector3d& x) {
                           return Eigen::Vector3d(Eigen::Vector3d::UnitZ().cross(x - centroid) / radius);
                         },
                         Eigen::Vector3d::UnitZ() / radius});
      motions.push_back({net.local_dimensions == 3 ? "horizontal scale" : "scale",
                         [centroid, radius](const Eigen::Vector3d& x) {
                           Eigen::Vector3d d = (x - centroid) / radius;
                           d.z() = 0.0;
                           return d;
                         },
                         Eigen::Vector3d::Zero()});
    }
    if (net.local_dimensions == 3) {
      // Angles alone keep a 3-D network's shape at any size: the uniform
      // scale is the horizontal and the vertical one together.
      motions.push_back({"vertical scale",
                         [centroid, radius](const Eigen::Vector3d& x) {
                           return Eigen::Vector3d(0.0, 0.0, (x.z() - centroid.z()) / radius);
                         },
                         Eigen::Vector3d::Zero()});
    }
  }
  return motions;
}

}  // namespace

DatumVectors datum_vectors(const NetworkProblem& p, const UnknownLayout& layout) {
  const auto& net = p.net;
  const bool ellipsoidal = net.space == NetworkSpace::ellipsoidal;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (p.station_used[s]) centroid += p.states[s].x, ++n;
  }
  centroid /= static_cast<double>(std::max<std::size_t>(n, 1));
  double radius2 = 0.0;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (p.station_used[s]) radius2 += (p.states[s].x - centroid).squaredNorm();
  }
  const double radius = std::max(1.0, std::sqrt(radius2 / static_cast<double>(std::max<std::size_t>(n, 1))));

  const std::vector<Motion> motions = datum_motions(net, centroid, radius);
  DatumVectors dv;
  dv.g = Eigen::MatrixXd::Zero(layout.count, static_cast<Eigen::Index>(motions.size()));
  for (std::size_t k = 0; k < motions.size(); ++k) {
    dv.names.push_back(motions[k].name);
    // Unit RMS motion over the stations reached, whatever the layout (a
    // combination means the same motion over every layout).
    double rms2 = 0.0;
    for (std::size_t s = 0; s < net.stations.size(); ++s) {
      if (!p.station_used[s]) continue;
      Eigen::Vector3d moved = motions[k].move(p.states[s].x);
      for (int c = 0; c < 3; ++c) {
        if (!estimated_component(net, c)) moved(c) = 0.0;  // (a local network's absent axes)
      }
      rms2 += moved.squaredNorm();
    }
    const double unit = rms2 > 0.0 ? 1.0 / std::sqrt(rms2 / static_cast<double>(std::max<std::size_t>(n, 1))) : 1.0;
    for (std::size_t s = 0; s < net.stations.size(); ++s) {
      if (!p.station_used[s]) continue;
      const Eigen::Vector3d local = unit * (p.states[s].axes * motions[k].move(p.states[s].x));
      for (int c = 0; c < 3; ++c) {
        const Index u = layout.station[s][static_cast<std::size_t>(c)];
        if (u >= 0) dv.g(u, static_cast<Eigen::Index>(k)) = local(c);
      }
    }
    // The group's datum moves with the stations, so that its values stay
    // as they are: its translation, rotation and scale take up the motion
    // (to first order), the rates none of it.
    if (ellipsoidal && !layout.helmert.empty()) {
      const Eigen::Vector3d t = p.helmert_pivot + p.helmert.head<3>();  // where the pivot lies in the network's frame
      Eigen::Matrix<double, 7, 1> d = Eigen::Matrix<double, 7, 1>::Zero();
      if (k < 3) {
        d.head<3>() = Eigen::Vector3d::Unit(static_cast<int>(k));
      } else if (k < 6) {
        const Eigen::Vector3d e = Eigen::Vector3d::Unit(static_cast<int>(k) - 3);
        d.head<3>() = e.cross(t - centroid) / radius;
        d(static_cast<Eigen::Index>(k)) = 1.0 / radius;
      } else {
        d.head<3>() = (t - centroid) / radius;
        d(6) = 1.0 / radius;
      }
      for (Eigen::Index j = 0; j < 7; ++j) dv.g(layout.helmert[static_cast<std::size_t>(j)], static_cast<Eigen::Index>(k)) = unit * d(j);
    }
    // A rotation turns the bearings at a station by its component about
    // the local vertical: the set's orientation turns with them.
    if (motions[k].rotation_axis.squaredNorm() > 0.0) {
      for (std::size_t set = 0; set < net.direction_sets.size(); ++set) {
        if (layout.orientation[set] < 0) continue;
        const auto& st = p.states[net.direction_sets[set].station];
        const double about_up = motions[k].rotation_axis.dot(st.local_from_xyz.row(2).transpose());
        dv.g(layout.orientation[set], static_cast<Eigen::Index>(k)) =
            unit * (ellipsoidal ? -about_up : net.axes.bearing_sign() * about_up);
      }
    }
  }
  dv.named = dv.g;
  dv.basis = Eigen::MatrixXd::Identity(dv.g.cols(), dv.g.cols());
  if (dv.g.cols() > 0 && dv.g.rows() > 0) {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(dv.g, Eigen::ComputeThinV);
    const Eigen::VectorXd& sv = svd.singularValues();
    Eigen::Index keep = 0;
    while (keep < sv.size() && sv(keep) > 1e-6 * sv(0)) ++keep;
    if (keep < dv.g.cols()) {
      // Unit RMS motion per column again: g·basis = U·√n.
      dv.basis = svd.matrixV().leftCols(keep) * sv.head(keep).cwiseInverse().asDiagonal() *
                 std::sqrt(static_cast<double>(std::max<std::size_t>(n, 1)));
      dv.g = dv.g * dv.basis;
    }
  }
  return dv;
}

std::string name_combination(const Eigen::VectorXd& e, const std::vector<std::string>& names) {
  std::string what;
  for (Eigen::Index j = 0; j < e.size(); ++j) {
    if (std::fabs(e(j)) >= 0.3 * e.cwiseAbs().maxCoeff()) what += (what.empty() ? "" : " with ") + names[static_cast<std::size_t>(j)];
  }
  return what;
}

namespace {

// What the measurements tell of the datum motions (the columns of g, unit
// RMS over the stations, over the unknowns of `layout`: the probe of every
// component) and what they could (datum_rank.hpp): the R factors of the
// rows A_j G_j and ‖A_j‖_F G_j, A_j a measurement's whitened rows over its
// unknowns and G_j the motions there. In the canonical order, in chunks on
// `jobs` threads folded in turn: the same bits for any order of the input
// and any number of threads.
struct DatumInformation {
  Eigen::MatrixXd measured, reference;
};

DatumInformation datum_information(const NetworkProblem& p, const UnknownLayout& layout, const Eigen::MatrixXd& g, int jobs) {
  const Eigen::Index d = g.cols();
  std::vector<std::size_t> active;
  for (std::size_t mi : p.order) {
    if (p.active[mi]) active.push_back(mi);
  }
  constexpr std::size_t kChunk = 4096;
  const std::size_t chunks = (active.size() + kChunk - 1) / kChunk;
  std::vector<RowsR> measured(chunks, RowsR(d)), reference(chunks, RowsR(d));
  for_chunks(active.size(), kChunk, jobs, [&](std::size_t begin, std::size_t end) {
    const std::size_t chunk = begin / kChunk;
    for (std::size_t k = begin; k < end; ++k) {
      const MeasurementRows r = p.linearize(active[k], layout);
      Eigen::MatrixXd gj(static_cast<Eigen::Index>(r.unknowns.size()), d);
      for (std::size_t c = 0; c < r.unknowns.size(); ++c) gj.row(static_cast<Eigen::Index>(c)) = g.row(r.unknowns[c]);
      measured[chunk].add(r.a * gj);
      reference[chunk].add(r.a.norm() * gj);
    }
  });
  RowsR all_measured(d), all_reference(d);
  for (std::size_t c = 0; c < chunks; ++c) {
    all_measured.add(measured[c]);
    all_reference.add(reference[c]);
  }
  return {all_measured.r(), all_reference.r()};
}

// The ratio (datum_rank.hpp: what a combination is told over what a
// typical station could be told at most) below which a combination of the datum motions is
// undefined: the factorization's pivots are then within a hundred roundings
// of nothing (sparse_factor's relative pivot check is the same 10⁻¹⁴).
// Rounding leaves a motion nothing measures near n·10⁻³²; a datum held by
// constraints of 100 m among millimetre baselines is near 10⁻¹⁰, by 1 km
// holds 10⁻¹², by a GNSS point of 3 m on one station 10⁻⁷: for a datum held
// at one station, the same for ten stations or a million. Below kWeakDatumRelative (a combination
// told at less than a millionth of what a typical station is told)
// it is defined, weakly, and named in a warning with the standard
// deviation it then has: a terrestrial network with no azimuth, turned
// about the vertical only by the convergence of the ellipsoid's normals,
// is near 10⁻⁸.
constexpr double kUndefinedDatumRelative = 1e-14;
constexpr double kWeakDatumRelative = 1e-6;

// How closely double precision resolves the standard deviation of a datum
// combination of this ratio in a network of n stations: the
// factorization's rounding along it grows as √n times a station's, about
// ε √n / (4 ratio) (measured: one station of 900, joined by baselines of
// millimetres, held at 1 km and 3 km, ratio 6·10⁻¹³ and 6·10⁻¹⁴: σ 0.2 % and
// 1.9 % off, this says 0.3 % and 3 %; held at 6 km the iteration no longer
// converges). Past kDatumResolution a warning says so; past
// kUnresolvedDatum the combination is undefined, as good as nothing.
double datum_resolution(double ratio, std::size_t stations) {
  return std::numeric_limits<double>::epsilon() * std::sqrt(static_cast<double>(std::max<std::size_t>(stations, 1))) / (4.0 * ratio);
}
constexpr double kDatumResolution = 1e-3;
// Above this ratio a combination is told of by the measurements, weakly,
// rather than left to their rounding (n·10⁻³² in the R factors; the
// positions' own rounding in ECEF, 10⁻⁹ m against a network's radius,
// under 10⁻²⁰ for stations 10 m apart).
constexpr double kToldOf = 1e-18;
constexpr double kUnresolvedDatum = 0.05;

// The combinations of the motions (columns over g's columns) that neither
// the measurements nor the constraints define to `below` of what a typical
// station is told (datum_rank.hpp), weakest first: a fixed component
// defines any motion that moves it; weighted constraints tell 1/σ² per
// component held. `probe` is the layout of every component (g's rows).
DatumRank undefined_datum(const NetworkProblem& p, const UnknownLayout& probe, const Eigen::MatrixXd& g, const DatumInformation& info,
                          double below) {
  const auto& net = p.net;
  const Eigen::Index d = g.cols();
  std::vector<Eigen::RowVectorXd> fixed_rows;
  RowsR weighted(d);
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(d, d);
  std::size_t stations = 0;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (!p.station_used[s]) continue;
    ++stations;
    for (int c = 0; c < 3; ++c) {
      const Index u = probe.station[s][static_cast<std::size_t>(c)];
      if (u >= 0) gram.noalias() += g.row(u).transpose() * g.row(u);
    }
    if (p.aside) continue;
    const auto& con = net.stations[s].constraint;
    for (int k = 0; k < 3; ++k) {
      if (con.code[static_cast<std::size_t>(k)] != 'C') continue;
      const Index u = probe.station[s][static_cast<std::size_t>(constrained_component(net.space, k))];
      if (u < 0) continue;
      const double sigma = con.sigma_m[static_cast<std::size_t>(k)];
      if (sigma > 0.0) {
        weighted.add(Eigen::MatrixXd(g.row(u) / sigma));
      } else {
        fixed_rows.push_back(g.row(u));
      }
    }
  }
  Eigen::MatrixXd fixed(static_cast<Eigen::Index>(fixed_rows.size()), d);
  for (std::size_t k = 0; k < fixed_rows.size(); ++k) fixed.row(static_cast<Eigen::Index>(k)) = fixed_rows[k];
  return weak_combinations(fixed, gram, stations, info.measured, weighted.r(), info.reference, below);
}

// The same span, as orthogonal motions of 1 m RMS at the stations: v (vᵀ T v / n)^(−1/2), T the motions' Gram matrix
// over the probe's station unknowns.
Eigen::MatrixXd unit_motions(const NetworkProblem& p, const UnknownLayout& probe, const Eigen::MatrixXd& g, const Eigen::MatrixXd& v) {
  if (v.cols() == 0) return v;
  Eigen::MatrixXd gv = Eigen::MatrixXd::Zero(g.rows(), v.cols());
  std::size_t stations = 0;
  for (std::size_t s = 0; s < p.net.stations.size(); ++s) {
    if (!p.station_used[s]) continue;
    ++stations;
    for (int c = 0; c < 3; ++c) {
      const Index u = probe.station[s][static_cast<std::size_t>(c)];
      if (u >= 0) gv.row(u) = g.row(u) * v;
    }
  }
  const Eigen::MatrixXd t = gv.transpose() * gv / static_cast<double>(std::max<std::size_t>(stations, 1));
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> te(t);
  return v * te.operatorInverseSqrt();
}

// What probing the datum found (probe_datum): the motions over the layout
// of every component, what the measurements and constraints tell of them,
// and the combinations they leave undefined (the first `below` of weak's).
struct DatumProbe {
  UnknownLayout probe;
  DatumVectors dv;
  DatumRank weak;
  std::size_t stations = 0;
  std::size_t below = 0;
  Eigen::MatrixXd undefined;
  std::vector<std::string> names;
  std::size_t unresolved = 0;
};

DatumProbe probe_datum(const NetworkProblem& p, int jobs) {
  const auto& net = p.net;
  DatumProbe d;
  d.probe = make_layout(p, true);
  d.dv = datum_vectors(p, d.probe);
  const DatumInformation info = datum_information(p, d.probe, d.dv.g, jobs);
  d.weak = undefined_datum(p, d.probe, d.dv.g, info, kWeakDatumRelative);
  const DatumRank& weak = d.weak;
  std::size_t& stations = d.stations;
  for (std::size_t st = 0; st < net.stations.size(); ++st) stations += p.station_used[st] ? 1u : 0u;
  std::size_t& below = d.below;
  while (below < weak.ratio.size() &&
         (weak.ratio[below] < kUndefinedDatumRelative || datum_resolution(weak.ratio[below], stations) > kUnresolvedDatum)) {
    ++below;
  }
  d.undefined = unit_motions(p, d.probe, d.dv.g, weak.combinations.leftCols(static_cast<Eigen::Index>(below)));
  for (Eigen::Index k = 0; k < d.undefined.cols(); ++k) d.names.push_back(name_combination(d.dv.basis * d.undefined.col(k), d.dv.names));
  // (Those told of, by measurements or weighted constraints, above
  // rounding but too weakly for double precision, say so.)
  for (std::size_t k = 0; k < below; ++k) d.unresolved += weak.ratio[k] >= kToldOf ? 1u : 0u;
  return d;
}

// What the constraints leave undefined (d.undefined, with no --free) is
// held by the input's own datum stations, or refused by name.
void hold_undefined_datum(NetworkProblem& p, const DatumProbe& d) {
  const auto& net = p.net;
  const auto& o = p.o;
  const std::string where = net.source_name;
  const DatumRank& weak = d.weak;
  const std::vector<std::string>& names = d.names;
  if (!net.datum_stations.empty()) {
    // What the constraints leave undefined is held by the input's
    // own datum stations (GNU Gama's constrained points): the
    // minimum-norm solution over them, the fixed components kept.
    p.free = true;
    for (const auto& ds : net.datum_stations) {
      if (p.station_used[ds.station]) p.inner.push_back(ds.station), p.inner_components.push_back(ds.components);
    }
    if (p.inner.empty()) {
      throw Error(ErrorKind::input, "E_DATUM_DEFECT",
                  where + ": the datum is not defined and none of the input's datum stations has a measurement");
    }
  } else {
    std::string list;
    for (const auto& x : names) list += (list.empty() ? "" : "; ") + x;
    const std::string weakly = "at " + fmt(weak.ratio[d.below - 1], 2) +
                               " of what a typical station is told or less, which double precision does not resolve "
                               "in a network of " + std::to_string(d.stations) + " stations";
    const std::string what =
        d.unresolved == names.size()
            ? "the datum is not defined to what double precision resolves: the measurements and constraints tell the " + list +
                  " only " + weakly
            : "the datum is not defined: neither the measurements nor the constraints fix the " + list +
                  (names.size() == 1 ? "" : " (" + std::to_string(names.size()) + " combinations)") +
                  (d.unresolved > 0 ? "; " + std::to_string(d.unresolved) + " of them they tell only " + weakly : std::string());
    throw Error(ErrorKind::input, "E_DATUM_DEFECT",
                where + ": " + what +
                    (o.helmert ? "; the Helmert of group " + o.helmert->name +
                                     " takes up the datum its measurements would give: constrain stations "
                                     "(--constrain ID=CCC[,SIGMA_M]) or add measurements in the network's frame"
                               : "; constrain stations (--constrain ID=CCC[,SIGMA_M]) or adjust it as a free network (--free)"));
  }
}

// Defined by the measurements, but weakly: named, with the
// standard deviation it then has at least. A datum held by weighted
// constraints is the user's business, unless it is held so weakly
// that double precision cannot resolve its standard deviation: the
// factorization's rounding along it grows as √n times a station's
// (measured: a 3 km hold at one of 900 stations of millimetre
// baselines, ratio 6·10⁻¹⁴, gives its σ 1.9 % off).
std::vector<std::string> weak_datum_warnings(const DatumProbe& d) {
  std::vector<std::string> datum_warnings;
  const DatumRank& weak = d.weak;
  const DatumVectors& dv = d.dv;
  const UnknownLayout& probe = d.probe;
  const std::size_t stations = d.stations;
  for (Eigen::Index k = static_cast<Eigen::Index>(d.below); k < weak.combinations.cols(); ++k) {
    const auto c = static_cast<std::size_t>(k);
    const double resolved = datum_resolution(weak.ratio[c], stations);
    const bool by_measurements = weak.measured[c] >= weak.weighted[c];
    if (!by_measurements && resolved <= kDatumResolution) continue;
    const Eigen::VectorXd y = weak.combinations.col(k);
    double motion2 = 0.0;
    const Eigen::VectorXd gy = dv.g * y;
    for (std::size_t uk = 0; uk < probe.owner.size(); ++uk) {
      if (probe.owner[uk].second < 3) motion2 += gy(static_cast<Eigen::Index>(uk)) * gy(static_cast<Eigen::Index>(uk));
    }
    const double rms = std::sqrt(motion2 / static_cast<double>(std::max<std::size_t>(stations, 1)));
    const double told = weak.measured[c] + weak.weighted[c];
    const std::string sigma = fmt_m(told > 0.0 ? rms / std::sqrt(told) : std::numeric_limits<double>::infinity());
    const std::string precision =
        resolved > kDatumResolution ? "; double precision resolves that standard deviation only to about " +
                                          fmt(100.0 * resolved, 2) + " %"
                                    : std::string();
    if (by_measurements) {
      datum_warnings.push_back("the datum's " + name_combination(dv.basis * y, dv.names) +
                               " is defined only weakly by the measurements: they tell it at " + fmt(weak.ratio[c], 2) +
                               " of what a typical station is told; its standard deviation is at least " + sigma +
                               " at the stations (RMS)" + precision + ": constrain stations or add measurements that fix it");
    } else {
      datum_warnings.push_back("the datum's " + name_combination(dv.basis * y, dv.names) +
                               " is held by the weighted constraints alone, at " + fmt(weak.ratio[c], 2) +
                               " of what a typical station is told (its standard deviation " + sigma +
                               " at the stations, RMS)" + precision + ": hold it with smaller standard deviations");
    }
  }
  return datum_warnings;
}

}  // namespace

void define_datum(NetworkProblem& p, std::vector<std::string>& datum_warnings, int jobs) {
  const auto& net = p.net;
  const auto& o = p.o;
  const DatumProbe d = probe_datum(p, jobs);
  if (!p.free && d.undefined.cols() > 0) hold_undefined_datum(p, d);
  p.defect_motions = d.dv.basis * d.undefined;
  p.defect = datum_vectors(p, p.layout).named * p.defect_motions;  // over the unknowns (no fixed component moves)
  p.defect_names = d.names;
  p.motion_names = d.dv.names;
  if (p.free && p.defect.cols() > 0) {
    check_inner_stations(p, net.datum_stations.empty() || o.free);
    choose_anchors(p);
  }
  datum_warnings = weak_datum_warnings(d);
}

std::string datum_in_words(const NetworkProblem& p) {
  const auto& net = p.net;
  const std::size_t d = static_cast<std::size_t>(p.defect.cols());
  std::size_t fixed = 0, weighted = 0;
  for (std::size_t s = 0; s < net.stations.size(); ++s) {
    if (!p.station_used[s] || p.aside) continue;
    const auto& con = net.stations[s].constraint;
    for (int k = 0; k < 3; ++k) {
      if (con.code[static_cast<std::size_t>(k)] != 'C') continue;
      (con.sigma_m[static_cast<std::size_t>(k)] > 0.0 ? weighted : fixed) += 1;
    }
  }
  if (p.free && d > 0 && !p.aside) {
    std::string list;
    for (const auto& x : p.defect_names) list += (list.empty() ? "" : "; ") + x;
    return std::to_string(fixed) + " coordinate component" + (fixed == 1 ? "" : "s") + " fixed, " +
           std::to_string(weighted) + " held with a standard deviation; what they leave undefined (" + list +
           ") held by the minimum-norm correction of the input's " + std::to_string(p.inner.size()) +
           " datum station" + (p.inner.size() == 1 ? "" : "s");
  }
  if (p.free && d > 0) {
    std::string list;
    for (const auto& x : p.defect_names) list += (list.empty() ? "" : "; ") + x;
    return "free network: " + list + " held by inner constraints over " + std::to_string(p.inner.size()) + " station" +
           (p.inner.size() == 1 ? "" : "s");
  }
  // Positions measured with their covariance (GNSS point clusters) hold
  // the datum as weighted constraints do: say so, or "0 fixed, 0 held"
  // reads as a network held by nothing.
  std::size_t clusters = 0;
  std::vector<char> positioned(net.stations.size(), 0);
  for (std::size_t mi = 0; mi < net.measurements.size(); ++mi) {
    const auto& m = net.measurements[mi];
    if (!p.active[mi] || m.kind != geodesy::MeasurementKind::gnss_points) continue;
    ++clusters;
    for (std::size_t st : m.stations) positioned[st] = 1;
  }
  const auto points = static_cast<std::size_t>(std::count(positioned.begin(), positioned.end(), 1));
  const std::string by_positions =
      clusters == 0 ? ""
                    : "; positions of " + std::to_string(points) + " station" + (points == 1 ? "" : "s") + " measured in " +
                          std::to_string(clusters) + " GNSS point cluster" + (clusters == 1 ? "" : "s") + " with their covariance";
  return std::to_string(fixed) + " coordinate component" + (fixed == 1 ? "" : "s") + " fixed, " +
         std::to_string(weighted) + " held with a standard deviation" + by_positions +
         (p.free ? " (free network: the measurements define the datum)" : "");
}

}  // namespace geoanchor::solver
