#include "geoanchor/workflow/uncertainty.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <limits>

#include "geoanchor/io/json_input.hpp"

namespace geoanchor::workflow {

std::optional<Eigen::Matrix3d> propagated_covariance_m2(const io::TransformFile& t, const geodesy::EcefPosition& x,
                                                        std::optional<geodesy::DecimalYear> epoch, bool inverse) {
  if (!t.fit || t.fit->sigmas.empty()) return std::nullopt;
  const io::FitRecord& f = *t.fit;
  // The parameters as the file spells them (canonical keys), to perturb one at a time.
  io::TransformFile plain = t;
  plain.fit.reset();
  nlohmann::json doc = io::parse_json_strict<nlohmann::json>(io::to_json_text(plain), "propagation");
  nlohmann::json& params = doc.at("parameters");
  for (const char* derived : {"origin_lat_deg", "origin_lon_deg", "origin_h_m"}) params.erase(derived);
  // The statements derived from the parameters would contradict the perturbed ones.
  for (const char* derived : {"proj_pipeline", "wkt2", "projjson", "alternatives", "epsg_method"}) doc.erase(derived);

  std::vector<std::string> names;
  std::vector<double> sigma;
  for (const auto& [name, s] : f.sigmas) {
    if (!(s > 0.0)) continue;  // a parameter known exactly adds nothing
    if (!params.contains(name)) return Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
    names.push_back(name);
    sigma.push_back(s);
  }
  const auto n = static_cast<Eigen::Index>(names.size());
  Eigen::MatrixXd j(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto iu = static_cast<std::size_t>(i);
    Eigen::Vector3d side[2];
    for (int s = 0; s < 2; ++s) {
      nlohmann::json d = doc;
      d["parameters"][names[iu]] = params.at(names[iu]).get<double>() + (s == 0 ? -sigma[iu] : sigma[iu]);
      const io::TransformFile p = io::parse_transform_json(d.dump(), "propagation");
      side[s] = p.apply(x, epoch, inverse, "propagation").m;
    }
    // Central difference over ±σ: the change per σ of this parameter.
    j.col(i) = (side[1] - side[0]) / 2.0;
  }
  // Σθ in σ units is the correlation matrix: the file's, or the identity
  // where the file says "correlation": "none". A sigma'd parameter the
  // matrix does not cover has no correlation we could assume.
  Eigen::MatrixXd r = Eigen::MatrixXd::Identity(n, n);
  if (!f.uncorrelated) {
    std::vector<std::size_t> at;
    for (const auto& name : names) {
      const auto it = std::find(f.correlation_names.begin(), f.correlation_names.end(), name);
      if (it == f.correlation_names.end()) return Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
      at.push_back(static_cast<std::size_t>(it - f.correlation_names.begin()));
    }
    for (Eigen::Index a = 0; a < n; ++a) {
      for (Eigen::Index b = 0; b < n; ++b) {
        const auto ia = at[static_cast<std::size_t>(a)], ib = at[static_cast<std::size_t>(b)];
        if (ia >= f.correlation.size() || ib >= f.correlation[ia].size()) {
          return Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
        }
        r(a, b) = f.correlation[ia][ib];
      }
    }
  }
  return Eigen::Matrix3d(j * r * j.transpose());
}

}  // namespace geoanchor::workflow
