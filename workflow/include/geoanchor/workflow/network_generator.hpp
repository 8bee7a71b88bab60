#pragma once
// Generated GNSS networks for planning and benchmarks (`geoanchor adjust
// --generate N`, bench/adjust_bench): N stations on a jittered square grid
// over a region on GRS80, each joined by GNSS baselines to its 4–6 nearest
// neighbours; each baseline's covariance is drawn per baseline (east and
// north 1.5–3 mm with a correlation up to ±0.3, up about twice the
// horizontal), turned into ECEF at its first station, and its value is the
// truth plus noise drawn from that covariance. A few stations are held
// (CCC, at the truth); the others' a-priori positions are the truth plus
// 5 cm noise per axis. A few baselines carry a planted blunder (a fixed
// length in a random direction), no two within two baselines of each other.
// The same seed gives the same network.

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/io/atomic_file.hpp"

namespace geoanchor::workflow {

struct NetworkGeneratorOptions {
  std::size_t stations = 1000;
  std::uint64_t seed = 1;
  double center_lat_deg = 47.0, center_lon_deg = 8.0;
  double side_km = 1000.0;                 // the square region's side
  std::size_t held = 3;                    // stations held (CCC), spread over the region
  std::optional<std::size_t> blunders;     // default: stations / 1000, at least 1, at most 10
  double blunder_m = 0.10;
  std::string frame = "ITRF2014@2020.0";   // of the stations and the baselines (on GRS80)
};

struct PlantedBlunder {
  std::size_t measurement = 0;  // index into the network's measurements
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();  // added to ΔX ΔY ΔZ
};

struct GeneratedNetwork {
  geodesy::Network network;
  std::vector<Eigen::Vector3d> truth;  // per station, ECEF
  std::vector<PlantedBlunder> blunders;
};

// Throws geoanchor::Error (usage, E_OPTION) for fewer than 4 stations,
// more held stations or blunders than the network takes, a side or blunder
// that is not positive and finite, a centre off the Earth.
GeneratedNetwork generate_network(const NetworkGeneratorOptions& options);

// Writes PREFIX.stn.xml and PREFIX.msr.xml (DynaML), PREFIX.json
// (geoanchor.network/1), PREFIX.truth.csv (station, x_m, y_m, z_m, held)
// and PREFIX.blunders.csv (measurement number from 1 in the measurement
// files, from, to, dx_m, dy_m, dz_m) into `folder`, as one group (all or
// none). Returns the paths written.
std::vector<std::filesystem::path> write_generated_network(const GeneratedNetwork& generated, const std::filesystem::path& folder,
                                                           const std::string& prefix, io::Overwrite overwrite);

}  // namespace geoanchor::workflow
