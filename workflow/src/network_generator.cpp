// Generated GNSS networks (network_generator.hpp).

#include "geoanchor/workflow/network_generator.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <numeric>
#include <random>
#include <utility>

#include "geoanchor/base/error.hpp"
#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/local_frame.hpp"
#include "geoanchor/base/number_text.hpp"
#include "geoanchor/io/network/network_output.hpp"

namespace geoanchor::workflow {

namespace {

constexpr double kAprioriNoiseM = 0.05;       // per axis, the free stations' a-priori positions
constexpr double kHorizontalSigmaMinM = 0.0015, kHorizontalSigmaMaxM = 0.003;
constexpr double kMaxHorizontalCorrelation = 0.3;
constexpr double kVerticalOverHorizontal = 2.0;  // ± 10 %
constexpr int kNeighbourRings = 2;               // grid cells searched around a station for its nearest
constexpr int kBlunderSeparationHops = 2;

[[noreturn]] void bad(const std::string& what) { throw Error(ErrorKind::usage, "E_OPTION", what); }

// The options checked (a bad one throws, naming its flag), and the number
// of blunders to plant.
std::size_t checked_blunders(const NetworkGeneratorOptions& o) {
  const std::size_t n = o.stations;
  if (n < 4) bad("--generate " + std::to_string(n) + ": a network needs at least 4 stations");
  if (!(o.side_km > 0.0) || !std::isfinite(o.side_km)) bad("--side-km " + format_shortest(o.side_km) + ": expected a positive length");
  if (!(o.blunder_m > 0.0) || !std::isfinite(o.blunder_m)) bad("--blunder " + format_shortest(o.blunder_m) + ": expected a positive length");
  if (!(std::abs(o.center_lat_deg) <= 80.0) || !(std::abs(o.center_lon_deg) <= 180.0)) {
    bad("--center " + format_shortest(o.center_lat_deg) + "," + format_shortest(o.center_lon_deg) +
        ": expected a latitude within ±80° and a longitude within ±180°");
  }
  if (o.held < 1 || o.held > n / 2) bad("--held " + std::to_string(o.held) + ": expected 1 to half the stations (" + std::to_string(n / 2) + ")");
  const std::size_t blunders = o.blunders.value_or(std::clamp<std::size_t>(n / 1000, 1, 10));
  if (blunders > n / 20) bad("--blunders " + std::to_string(blunders) + ": at most one per 20 stations (" + std::to_string(n / 20) + ") can be kept apart");
  return blunders;
}

using Edges = std::vector<std::pair<std::size_t, std::size_t>>;  // baselines: station pairs (i < j)

// Baselines to each station's 4–6 nearest, each pair once.
Edges nearest_baselines(std::size_t n, std::size_t side, const std::vector<Eigen::Vector2d>& plane, std::mt19937_64& rng) {
  std::vector<std::pair<std::size_t, std::size_t>> edges;
  std::vector<std::pair<double, std::size_t>> candidates;
  for (std::size_t i = 0; i < n; ++i) {
    const long row = static_cast<long>(i / side), col = static_cast<long>(i % side);
    candidates.clear();
    for (long r = row - kNeighbourRings; r <= row + kNeighbourRings; ++r) {
      for (long c = col - kNeighbourRings; c <= col + kNeighbourRings; ++c) {
        if (r < 0 || c < 0 || c >= static_cast<long>(side)) continue;
        const std::size_t j = static_cast<std::size_t>(r) * side + static_cast<std::size_t>(c);
        if (j >= n || j == i) continue;
        candidates.push_back({(plane[j] - plane[i]).squaredNorm(), j});
      }
    }
    const std::size_t k = std::min<std::size_t>(candidates.size(), 4 + rng() % 3);
    std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(k), candidates.end());
    for (std::size_t m = 0; m < k; ++m) edges.push_back({std::min(i, candidates[m].second), std::max(i, candidates[m].second)});
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

// Joined into one network: each part beyond the first is tied to its
// nearest station of another part (rare on a jittered grid).
void join_parts(Edges& edges, std::size_t n, const std::vector<Eigen::Vector2d>& plane) {
  for (;;) {
    std::vector<std::size_t> parent(n);
    std::iota(parent.begin(), parent.end(), 0);
    const auto find = [&](std::size_t x) {
      while (parent[x] != x) x = parent[x] = parent[parent[x]];
      return x;
    };
    for (const auto& [p, q] : edges) parent[find(p)] = find(q);
    std::vector<std::pair<std::size_t, std::size_t>> ties;
    std::vector<bool> tied(n, false);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t root = find(i);
      if (root == find(0) || tied[root]) continue;
      double best = INFINITY;
      std::size_t to = 0;
      for (std::size_t j = 0; j < n; ++j) {
        if (find(j) == root) continue;
        const double d = (plane[j] - plane[i]).squaredNorm();
        if (d < best) best = d, to = j;
      }
      tied[root] = true;
      ties.push_back({std::min(i, to), std::max(i, to)});
    }
    if (ties.empty()) break;
    edges.insert(edges.end(), ties.begin(), ties.end());
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  }
}

// Blunders on baselines far apart (no station of one within two
// baselines of another's).
void plant_blunders(std::size_t blunders, const Edges& edges, const NetworkGeneratorOptions& o, std::mt19937_64& rng,
                    std::normal_distribution<double>& normal, GeneratedNetwork& g) {
  const std::size_t n = o.stations;
  auto& net = g.network;
  std::vector<std::vector<std::size_t>> adjacent(n);
  for (const auto& [p, q] : edges) adjacent[p].push_back(q), adjacent[q].push_back(p);
  std::vector<bool> near(n, false);
  std::size_t tries = 0;
  while (g.blunders.size() < blunders) {
    if (++tries > 100 * edges.size()) bad("--blunders " + std::to_string(blunders) + ": the network has no room to keep them apart");
    const std::size_t k = static_cast<std::size_t>(rng() % edges.size());
    const auto [p, q] = edges[k];
    if (near[p] || near[q]) continue;
    std::vector<std::size_t> ring{p, q};
    for (std::size_t s : ring) near[s] = true;
    for (int hop = 0; hop < kBlunderSeparationHops; ++hop) {
      std::vector<std::size_t> further;
      for (std::size_t s : ring) {
        for (std::size_t t : adjacent[s]) {
          if (!near[t]) near[t] = true, further.push_back(t);
        }
      }
      ring.swap(further);
    }
    Eigen::Vector3d direction(normal(rng), normal(rng), normal(rng));
    direction.normalize();
    PlantedBlunder b{k, o.blunder_m * direction};
    net.measurements[k].value += b.offset_m;
    g.blunders.push_back(b);
  }
  std::sort(g.blunders.begin(), g.blunders.end(), [](const auto& x, const auto& y) { return x.measurement < y.measurement; });
}

}  // namespace

GeneratedNetwork generate_network(const NetworkGeneratorOptions& o) {
  const std::size_t n = o.stations;
  const std::size_t blunders = checked_blunders(o);

  GeneratedNetwork g;
  auto& net = g.network;
  net.frame = geodesy::Frame::parse(o.frame, "the generator's frame");
  net.ellipsoid = geodesy::Ellipsoid::grs80();
  net.ellipsoid_stated = true;
  net.source_name = "generated network (" + std::to_string(n) + " stations, seed " + std::to_string(o.seed) + ")";
  const geodesy::GeocentricConverter geocentric(net.ellipsoid);
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit_interval(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto uniform = [&](double a, double b) { return a + (b - a) * unit_interval(rng); };

  // Stations: a side × side grid filled row by row, each jittered within its cell.
  const std::size_t side = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(n))));
  const double spacing_m = o.side_km * 1000.0 / static_cast<double>(side);
  const double a = net.ellipsoid.a_m(), e2 = net.ellipsoid.e2();
  const double lat0 = o.center_lat_deg * std::numbers::pi / 180.0;
  const double w = std::sqrt(1.0 - e2 * std::sin(lat0) * std::sin(lat0));
  const double meridian = a * (1.0 - e2) / (w * w * w), prime = a / w;
  std::vector<Eigen::Vector2d> plane(n);  // east, north from the centre (m)
  std::vector<Eigen::Matrix3d> enu(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double col = static_cast<double>(i % side), row = static_cast<double>(i / side);
    plane[i] = {(col + 0.5 + uniform(-0.3, 0.3)) * spacing_m - 0.5 * o.side_km * 1000.0,
                (row + 0.5 + uniform(-0.3, 0.3)) * spacing_m - 0.5 * o.side_km * 1000.0};
    const double lat = lat0 + plane[i].y() / meridian;
    const double lon = o.center_lon_deg * std::numbers::pi / 180.0 + plane[i].x() / (prime * std::cos(lat));
    const double h = uniform(100.0, 1500.0);
    const geodesy::GeodeticPosition p{geodesy::Angle::radians(lat), geodesy::Angle::radians(lon), geodesy::EllipsoidalHeight{h}};
    g.truth.push_back(geocentric.ecef_from_geodetic(p).m);
    enu[i] = geodesy::enu_from_ecef_rotation(p.lat, p.lon);
    geodesy::NetworkStation s;
    s.id = "G" + std::to_string(i + 1);
    s.position = g.truth[i] + kAprioriNoiseM * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    s.source = "generated station " + std::to_string(i + 1);
    net.stations.push_back(std::move(s));
  }
  // Held stations spread along the grid's order (first, …, last).
  for (std::size_t k = 0; k < o.held; ++k) {
    const std::size_t i = o.held == 1 ? n / 2 : k * (n - 1) / (o.held - 1);
    net.stations[i].constraint.code = {'C', 'C', 'C'};
    net.stations[i].position = g.truth[i];
  }

  Edges edges = nearest_baselines(n, side, plane, rng);
  join_parts(edges, n, plane);

  for (std::size_t k = 0; k < edges.size(); ++k) {
    const auto [i, j] = edges[k];
    const double se = uniform(kHorizontalSigmaMinM, kHorizontalSigmaMaxM), sn = uniform(kHorizontalSigmaMinM, kHorizontalSigmaMaxM);
    const double rho = uniform(-kMaxHorizontalCorrelation, kMaxHorizontalCorrelation);
    const double su = kVerticalOverHorizontal * std::sqrt(se * sn) * uniform(0.9, 1.1);
    Eigen::Matrix3d c_enu;
    c_enu << se * se, rho * se * sn, 0.0, rho * se * sn, sn * sn, 0.0, 0.0, 0.0, su * su;
    Eigen::Matrix3d c = enu[i].transpose() * c_enu * enu[i];
    c = (0.5 * (c + c.transpose())).eval();
    const Eigen::Matrix3d l = c.llt().matrixL();
    geodesy::NetworkMeasurement m;
    m.kind = geodesy::MeasurementKind::gnss_baselines;
    m.stations = {i, j};
    m.value = g.truth[j] - g.truth[i] + l * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    m.covariance = c;
    m.frame = net.frame;
    m.source = "generated baseline " + std::to_string(k + 1);
    net.measurements.push_back(std::move(m));
  }

  plant_blunders(blunders, edges, o, rng, normal, g);
  return g;
}

std::vector<std::filesystem::path> write_generated_network(const GeneratedNetwork& g, const std::filesystem::path& folder,
                                                           const std::string& prefix, io::Overwrite overwrite) {
  io::check_writable_network(g.network);
  const auto path = [&](const char* suffix) { return folder / (prefix + suffix); };
  const std::vector<std::filesystem::path> paths{path(".stn.xml"), path(".msr.xml"), path(".json"), path(".truth.csv"),
                                                 path(".blunders.csv")};
  std::vector<std::unique_ptr<io::AtomicOutputFile>> files;
  for (const auto& p : paths) files.push_back(std::make_unique<io::AtomicOutputFile>(p, overwrite));
  io::write_dynaml_stations(g.network, files[0]->stream());
  io::write_dynaml_measurements(g.network, files[1]->stream());
  io::write_network_json(g.network, files[2]->stream());
  auto& truth = files[3]->stream();
  truth << "station,x_m,y_m,z_m,held\n";
  for (std::size_t i = 0; i < g.truth.size(); ++i) {
    const auto& s = g.network.stations[i];
    truth << s.id << ',' << format_shortest(g.truth[i].x()) << ',' << format_shortest(g.truth[i].y()) << ','
          << format_shortest(g.truth[i].z()) << ',' << (s.constraint.any() ? "true" : "false") << '\n';
  }
  auto& blunders = files[4]->stream();
  blunders << "measurement,from,to,dx_m,dy_m,dz_m\n";
  for (const auto& b : g.blunders) {
    const auto& m = g.network.measurements[b.measurement];
    blunders << b.measurement + 1 << ',' << g.network.stations[m.stations[0]].id << ',' << g.network.stations[m.stations[1]].id << ','
             << format_shortest(b.offset_m.x()) << ',' << format_shortest(b.offset_m.y()) << ',' << format_shortest(b.offset_m.z())
             << '\n';
  }
  std::vector<io::AtomicOutputFile*> group;
  for (auto& f : files) group.push_back(f.get());
  io::publish_together(group);
  return paths;
}

}  // namespace geoanchor::workflow
