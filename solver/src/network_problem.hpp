#pragma once
// The network adjustment's problem (network_adjustment.hpp): its unknowns
// (UnknownLayout), the state the Gauss–Newton iteration moves
// (NetworkProblem), each measurement's linearized and whitened rows, the
// constraints held with a standard deviation, and the corrections that move
// the state.
//
// Private to solver.

#include <Eigen/Core>

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "geoanchor/geodesy/geocentric.hpp"
#include "geoanchor/geodesy/network.hpp"
#include "geoanchor/solver/network_adjustment.hpp"
#include "network_model.hpp"

namespace geoanchor::solver {

using Clock = std::chrono::steady_clock;
inline double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
using Index = std::int64_t;

// Measurements per chunk of work shared among threads (parallel.hpp).
inline constexpr std::size_t kMeasurementChunk = 512;

// The stations' unknowns: per station the index of each local component's
// correction (east, north, up | x, y, z), −1 where none; per direction set
// its orientation's.
struct UnknownLayout {
  std::vector<std::array<Index, 3>> station;
  std::vector<Index> orientation;
  std::vector<Index> helmert;  // AdjustOptions::helmert's parameters (7 or 14), in HelmertGroup's order
  Index count = 0;
  // What each unknown is: the station (or set) and the component (3: an
  // orientation; 4: a Helmert parameter, `first` its index).
  std::vector<std::pair<std::size_t, int>> owner;
  bool operator==(const UnknownLayout&) const = default;
};

const char* component_name(geodesy::NetworkSpace space, int c);

// The local component a constraint letter holds: latitude, longitude,
// height are north, east, up; a local network's x, y, z are themselves.
int constrained_component(geodesy::NetworkSpace space, int k);

// Whether a local network estimates component c.
bool estimated_component(const geodesy::Network& net, int c);

std::string fmt_m(double v);

extern const char* const kHelmertNames[14];

// One measurement's rows, linearized: its unknowns and the whitened design
// rows over them, the whitened misclosure (observed − computed).
struct MeasurementRows {
  std::vector<Index> unknowns;
  Eigen::MatrixXd a;  // whitened, rows × unknowns.size()
  Eigen::VectorXd l;  // whitened misclosure
  Eigen::VectorXd computed;
};

struct NetworkProblem {
  const geodesy::Network& net;
  const AdjustOptions& o;
  geodesy::GeocentricConverter geocentric;
  std::vector<StationState> states;
  std::vector<double> orientations;
  Eigen::VectorXd helmert;        // AdjustOptions::helmert's parameters (SI) about helmert_pivot, p0 then the rates
  Eigen::Vector3d helmert_pivot = Eigen::Vector3d::Zero();  // the group's stations' a-priori centroid
  std::vector<int> helmert_slot;  // per measurement: its place in the group, −1 outside it
  std::vector<Eigen::MatrixXd> whitening;  // per measurement: W with Wᵀ W = C⁻¹
  std::vector<bool> active;                // measurements in the adjustment
  // Measurements removed by data snooping whose entries stay in the normal
  // matrix as zeros, so that its pattern (and its ordering and symbolic
  // analysis) is the first pass's: the next pass refactors numerically only.
  std::vector<bool> pattern_only;
  std::vector<bool> station_used;
  UnknownLayout layout;
  bool aside = false;  // --free: the input's station constraints are set aside
  bool free = false;   // the datum (or what the constraints leave of it) by inner constraints
  std::vector<std::size_t> inner;          // free: the inner-constraint stations
  std::vector<std::array<bool, 3>> inner_components;  // their components in the inner constraints
  Eigen::MatrixXd defect;                  // free: the undefined datum directions over the unknowns (u × d)
  std::vector<std::size_t> anchor;         // free: the stations the defect is held at while iterating
  std::vector<std::array<bool, 3>> anchor_components;  // their components that hold it
  std::vector<std::string> defect_names;
  Eigen::MatrixXd defect_motions;          // the defect's columns over the named motions (DatumVectors::named)
  std::vector<std::string> motion_names;
  // Every sum over measurements runs in this order (canonical_order: by
  // what each is, not where it is in the input), and the direction sets'
  // orientations are numbered in set_order: the same network in a shuffled
  // file gives the same bits.
  std::vector<std::size_t> order;
  std::vector<std::size_t> set_order;

  NetworkProblem(const geodesy::Network& n, const AdjustOptions& opt) : net(n), o(opt), geocentric(n.ellipsoid) {}

  MeasurementRows linearize(std::size_t mi) const { return linearize(mi, layout); }
  // The rows over the unknowns of `l` (the layout, or the datum's probe of
  // every component).
  MeasurementRows linearize(std::size_t mi, const UnknownLayout& l) const;

  // The constraint of station s along component c held with a sigma: its
  // whitened misclosure (a-priori − current, along the local axis) and unknown.
  struct Pseudo {
    Index unknown;
    double l;
  };
  std::vector<Pseudo> pseudo_observations() const;
  double pseudo_weight(Index unknown) const;
};

// Union-find over stations joined by a measurement.
std::vector<std::size_t> components_of(const NetworkProblem& p, std::size_t& count);

// The unknowns: with `all_free` every component of every station reached
// (the datum's probe: what the measurements alone determine), else those
// the constraints leave.
UnknownLayout make_layout(const NetworkProblem& p, bool all_free = false);

// Moves the stations and orientations by the unknowns' corrections; returns
// the largest station correction (metres) and its station.
std::pair<double, std::size_t> apply_corrections(NetworkProblem& p, const Eigen::VectorXd& dx);

}  // namespace geoanchor::solver
