// DrapeGrid: the mass-spring grid of Mozafary & Payvandy (2017) (user's view: docs/scenes.md).
//
// A square fabric of side W (m) and areal density rho_A (g/m^2) becomes an (n+1) x (n+1) grid,
//   n = max(2, floor(W / L0 + 0.5)) cells per side, spacing exactly L0 (the model fabric is
//   n L0 wide and unstretched at rest), particle (i, j) at (x, y, z) = (j L0, i L0, 0);
//   gravity along -z. Total mass rho_A (n L0)^2 lumped by area: interior weight 1, edge 1/2,
//   corner 1/4, normalised to the total.
// Springs (one common stiffness k, paper 1 "all springs share a common stiffness"):
//   structural (i,j)-(i,j+1), (i,j)-(i+1,j), rest L0;  shear: both cell diagonals, rest
//   sqrt(2) L0;  bending (i,j)-(i,j+2), (i,j)-(i+2,j), rest 2 L0.
//   Topology a = structural + shear + bending (paper Fig. 4), b = structural + shear (Fig. 5),
//   c = structural + bending (Fig. 6; no shear resistance: a mechanism that sags far more).
// Pins: four_corner holds the 4 corners; two_corner holds (0,0) and (0,n). With pin_span < 1
//   the two pins move symmetrically inward along x to span x n L0, linearly over
//   pin_move_time seconds (the "slack" hanging-sheet test); a seeded out-of-plane perturbation
//   of amplitude `perturbation` (m) may break the mirror symmetry of the flat start.
// Units: SI except areal density (g/m^2) and elongation limit (percent), as the paper gives them.
#pragma once

#include <string>
#include <vector>

#include "models/spring_network.hpp"

namespace knitsim {

enum class PinLayout { FourCorner, TwoCorner };
// What run_drape integrates: the whole grid; one half with the mirror condition on the mid-plane
// x = W/2 (four_corner or two_corner); one quarter of a four_corner grid with mirror conditions
// on both mid-planes; or one eighth with the diagonal mirror too (models/mirror_reduced.hpp; the
// result is unfolded).
// Auto: the largest mirror group the scene and its start have (src/scene/scene.hpp run_drape).
enum class DrapeSymmetry { None, Half, Quarter, Eighth, Auto };

struct DrapeParams {
  double width = 0.50;            // W, m (paper: 50 x 50 cm samples)
  double areal_density = 41.65;   // rho_A, g/m^2 (Table 2, sample 1)
  double stiffness = 852.0;       // k, N/m (Table 4, sample 1; Table 3 bounds 500-1200)
  double damping = 12.0;          // c, N s/m per particle (bounds 10-20)
  double elongation_limit = 5.0;  // eps_max, percent (bounds 5-20); 0 disables the limit
  double natural_length = 0.049;  // L0, m (4.9 cm; bounds 4-6 cm)
  char topology = 'a';            // 'a' | 'b' | 'c'
  PinLayout layout = PinLayout::FourCorner;
  double pin_span = 1.0;         // final pin distance / model width, (0, 1]
  double pin_move_time = 100.0;  // s, duration of the pin move when pin_span < 1
  double perturbation = 0.0;     // m, amplitude of the seeded initial z perturbation
  unsigned seed = 1;             // seed of that perturbation
  // auto | none | half | quarter | eighth (without perturbation; quarter and eighth
  // four_corner only; models/mirror_reduced.hpp). auto: the largest the scene allows.
  DrapeSymmetry symmetry = DrapeSymmetry::Auto;
  long max_particles = 4'000'000;  // refuse larger grids before allocating

  // Throws std::invalid_argument naming the field and the accepted range.
  void validate() const;
  // Cells per side n for these parameters.
  int cells() const;
};

// A measured fabric edge: particle indices in order from one end to the other.
struct GridEdge {
  std::string name;
  std::vector<int> particles;
};

struct DrapeGrid {
  DrapeParams params;
  int n = 0;  // cells per side; particle (i, j) has index i (n+1) + j
  SpringNetwork network;
  std::vector<GridEdge> edges;  // the boundary edges (top i=0, bottom i=n, left j=0, right j=n)
  int index(int i, int j) const { return i * (n + 1) + j; }
};

DrapeGrid build_drape_grid(const DrapeParams& params);

// The model's own limits at an end state: "" where they hold, else why not (one line).
//   max_strain (a fraction) above the elongation limit by more than kStrainLimitTolerance of
//     it: the limiting spring (100 k) lets a spring past L_max by 1/101 of the strain the
//     linear spring alone would take, so 10 % past it means a linear strain ~11 times the
//     limit -- a fabric the model no longer describes (e.g. model.stiffness = 1e-6);
//   a centre sag (m) larger than the model sheet's width n L0 (a sheet hung by its corners
//     cannot sag further than it is wide while its springs keep near their limit);
//   either figure not finite.
inline constexpr double kStrainLimitTolerance = 0.10;
std::string drape_limit_violation(const DrapeParams& params, double max_strain, double centre_sag);

// The continuous drape parameters (DrapeParams fields, same units: N/m, N s/m, percent, m).
enum class DrapeParameter { Stiffness, Damping, ElongationLimit, NaturalLength };
const char* to_string(DrapeParameter p);  // stiffness | damping | elongation_limit | natural_length

// d(network data)/dp of build_drape_grid(params) for one parameter p, with the pins' positions
// taken at time t, AT FIXED TOPOLOGY: n = cells() is held, although n = round(W / L0) jumps
// at L0 = W / (n + 1/2) (there the edges jump; this is the one-sided derivative inside a bracket).
//   Stiffness:       dk_s = 1 for every spring (one common k).
//   NaturalLength:   the whole grid scales with L0 at fixed n: d rest_s = rest_s / L0,
//                    dm_i = 2 m_i / L0 (total mass rho_A (n L0)^2), d pin = pin(t) / L0 (both
//                    ends of every pin path are multiples of L0).
//   ElongationLimit: d eps_max = 0.01 per percent (zero effect unless the limit is active).
//   Damping:         zero (c does not enter the static force).
SpringNetworkTangent drape_tangent(const DrapeGrid& grid, DrapeParameter p, double t);

const char* to_string(PinLayout layout);
const char* to_string(DrapeSymmetry symmetry);  // none | half | quarter | eighth | auto

}  // namespace knitsim
