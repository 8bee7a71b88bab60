// The Helmert group of a network adjustment (network_helmert.hpp).

#include "network_helmert.hpp"

#include <Eigen/Dense>

#include <string>
#include <vector>

#include "geoanchor/base/error.hpp"

namespace geoanchor::solver {

using geodesy::NetworkSpace;

namespace {

// [v]×: the matrix of v × ·.
Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

}  // namespace

GeocentricForm geocentric_form(const Eigen::VectorXd& about_pivot, const Eigen::Vector3d& c, bool rates) {
  const Eigen::Index n = about_pivot.size();
  const Eigen::Vector3d r = about_pivot.segment<3>(3);
  const double scale = 1.0 + about_pivot(6);
  const Eigen::Vector3d rc = (Eigen::Matrix3d::Identity() + cross_matrix(r)) * c;
  GeocentricForm g;
  g.parameters = about_pivot;
  g.parameters.head<3>() = c + about_pivot.head<3>() - scale * rc;
  g.j = Eigen::MatrixXd::Identity(n, n);
  g.j.block<3, 3>(0, 3) = scale * cross_matrix(c);  // ∂T/∂r = −(1 + s) ∂(R c)/∂r = (1 + s) [c]×
  g.j.block<3, 1>(0, 6) = -rc;
  if (rates) {
    const Eigen::Vector3d dr = about_pivot.segment<3>(10);
    const double ds = about_pivot(13);
    g.parameters.segment<3>(7) = about_pivot.segment<3>(7) - ds * rc + scale * cross_matrix(c) * dr;
    g.j.block<3, 3>(7, 3) = ds * cross_matrix(c);  // −ṡ ∂(R c)/∂r
    g.j.block<3, 1>(7, 6) = cross_matrix(c) * dr;  // ∂/∂s of (1 + s) [c]× ṙ
    g.j.block<3, 3>(7, 10) = scale * cross_matrix(c);
    g.j.block<3, 1>(7, 13) = -rc;
  }
  return g;
}

void into_group_datum(Evaluation& ev, bool points, const GeocentricForm& g, bool rates, double dt,
                      Eigen::MatrixXd& d_parameters) {
  Eigen::Matrix<double, 7, 1> q = g.parameters.head<7>();
  if (rates) q += dt * g.parameters.segment<7>(7);
  const Eigen::Vector3d t = q.head<3>(), r = q.segment<3>(3);
  const double scale = 1.0 + q(6);
  const Eigen::Matrix3d r_inv = (Eigen::Matrix3d::Identity() + cross_matrix(r)).inverse();
  const Eigen::Matrix3d a = r_inv / scale;
  const Eigen::Index rows = ev.computed.size();
  Eigen::MatrixXd d_geocentric = Eigen::MatrixXd::Zero(rows, rates ? 14 : 7);
  for (Eigen::Index k = 0; k + 2 < rows; k += 3) {
    const Eigen::Vector3d x = ev.computed.segment<3>(k);
    const Eigen::Vector3d y = a * (points ? Eigen::Vector3d(x - t) : x);
    ev.computed.segment<3>(k) = y;
    ev.d_local.middleRows(k, 3) = a * ev.d_local.middleRows(k, 3);
    Eigen::Matrix<double, 3, 7> d = Eigen::Matrix<double, 3, 7>::Zero();
    if (points) d.leftCols<3>() = -a;
    d.middleCols<3>(3) = r_inv * cross_matrix(y);  // ∂y/∂r = −R⁻¹ (∂R/∂r_i) y, ∂R/∂r_i = [e_i]×
    d.col(6) = -y / scale;
    d_geocentric.block(k, 0, 3, 7) = d;
    if (rates) d_geocentric.block(k, 7, 3, 7) = dt * d;
  }
  d_parameters = d_geocentric * g.j;
}

namespace {

// The estimate in the geocentric form, its covariance carried by J.
EstimatedHelmert geocentric_helmert(const Eigen::VectorXd& about_pivot, const Eigen::MatrixXd& covariance,
                                    const Eigen::Vector3d& c, bool rates) {
  const GeocentricForm g = geocentric_form(about_pivot, c, rates);
  EstimatedHelmert h;
  h.parameters = g.parameters;
  h.covariance = g.j * covariance * g.j.transpose();
  return h;
}

}  // namespace

void begin_helmert_group(NetworkProblem& p) {
  const auto& net = p.net;
  const auto& o = p.o;
  const std::string where = net.source_name;
  if (net.space != NetworkSpace::ellipsoidal) {
    throw Error(ErrorKind::usage, "E_OPTION", where + ": a Helmert transformation needs a network on the ellipsoid");
  }
  if (o.free) throw Error(ErrorKind::usage, "E_OPTION", "--estimate-helmert with --free: give the network's datum by constraints");
  p.helmert = Eigen::VectorXd::Zero(o.helmert->rates ? 14 : 7);
  p.helmert_slot.assign(net.measurements.size(), -1);
  for (std::size_t k = 0; k < o.helmert->measurements.size(); ++k) {
    const std::size_t mi = o.helmert->measurements[k];
    const auto kind = net.measurements.at(mi).kind;
    if (kind != geodesy::MeasurementKind::gnss_baselines && kind != geodesy::MeasurementKind::gnss_points) {
      throw Error(ErrorKind::input, "E_HELMERT_GROUP",
                  net.measurements[mi].source + ": " + geodesy::to_string(kind) + " in Helmert group " + o.helmert->name +
                      ": a datum transformation relates GNSS positions and baselines only");
    }
    p.helmert_slot[mi] = static_cast<int>(k);
  }
  std::size_t count = 0;
  std::vector<bool> seen(net.stations.size(), false);
  for (std::size_t mi : o.helmert->measurements) {
    for (std::size_t st : net.measurements[mi].stations) {
      if (seen[st]) continue;
      seen[st] = true;
      p.helmert_pivot += net.stations[st].position;
      ++count;
    }
  }
  if (count > 0) p.helmert_pivot /= static_cast<double>(count);
}

EstimatedHelmert estimated_helmert(const NetworkProblem& p, const NormalFactor& f) {
  const auto n_par = static_cast<Eigen::Index>(p.layout.helmert.size());
  Eigen::MatrixXd covariance(n_par, n_par);
  for (Eigen::Index i = 0; i < n_par; ++i) {
    for (Eigen::Index j = 0; j < n_par; ++j) {
      covariance(i, j) = f.inverse(p.layout.helmert[static_cast<std::size_t>(i)], p.layout.helmert[static_cast<std::size_t>(j)]);
    }
  }
  return geocentric_helmert(p.helmert, covariance, p.helmert_pivot, p.o.helmert->rates);
}

}  // namespace geoanchor::solver
