// agent bodies (SPEC §4.1): the body and spring genotypes, their validity, random draws, mutation
// with repair, the geometry an agent is built from, and the initial controller parameters (§4.3).
//
// The lattice is triangular, 4 rows × 7 columns; cell (r, c) has index r*7 + c and sits at
// (0.05·c + 0.025·(r mod 2), 0.05·r·√3/2) u. A body genotype is a 28-bit mask of cells (bit i =
// cell i): exactly 11 set, connected, no enclosed empty cell, exactly 21 lattice edges between set
// cells. A spring genotype is a 21-bit mask (bit s = spring s active), at least one set. The masses
// are the set cells in row-major order; the springs are the 21 lattice edges between them, in sorted
// (i < j) pair order.
//
// Shapes "up to translation": two valid placements are the same shape when their rest positions are
// equal after shifting min x and min y to 0, i.e. when one is a geometric translation of the other.
// The lattice is invariant under a shift by whole columns and under a shift by one row with a half
// column offset (0.025, 0.05·√3/2), so translating by one row keeps the shape. All placements of a
// shape give identical agent geometry (row-major mass order is (y, x) order, which a translation
// keeps); placement only matters to which shapes a mutation can reach.
//
// There are 94 valid placements and 20 shapes (checked against an independent enumeration). SPEC's
// "about 24" is the count when only shifts by whole columns and by two rows are identified (the four
// three-row shapes then count twice, once per row parity); those pairs are the same agent, so 20 it is.
// The 94 placements are found once per process by running over all C(28, 11) subsets with a
// bit-parallel edge count (≈ 0.06 s) and cached.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "common/rng.hpp"
#include "morph/agent.hpp"

namespace divcoll::morph {

// ---- lattice and body constants ------------------------------------------------------------------
inline constexpr int kRows = 4;
inline constexpr int kCols = 7;
inline constexpr int kCells = kRows * kCols;  // 28 body genotype bits
inline constexpr int kBodyCells = 11;         // masses per agent
inline constexpr int kBodyEdges = 21;         // springs per agent = spring genotype bits
inline constexpr uint32_t kCellMask = (1u << kCells) - 1;
inline constexpr uint32_t kSpringMask = (1u << kBodyEdges) - 1;

inline constexpr double kSpacing = 0.05;          // u, lattice spacing
inline constexpr double kAgentStiffness = 3e4;    // force/u, every agent spring
inline constexpr double kAgentDashpot = 0.0;      // every agent spring
inline constexpr double kActiveAmplitude = 0.15;  // relative actuation amplitude of an active spring

// both genotypes of an agent
struct Body {
  uint32_t cells = 0;    // 28 bits, bit r*7+c = cell (r, c)
  uint32_t springs = 0;  // 21 bits, bit s = spring s active
};

// ---- lattice -------------------------------------------------------------------------------------
// (x, y) u of cell index `cell` in [0, 28)
std::array<double, 2> cell_position(int cell);
// bit mask of the lattice neighbours of `cell`
uint32_t cell_neighbours(int cell);
// number of lattice edges between set cells of `cells`
int lattice_edges(uint32_t cells);

// ---- validity ------------------------------------------------------------------------------------
// true when `cells` satisfies §4.1; otherwise false and, if why is given, a sentence naming the first
// failed rule (checked in the order: stray bits, cell count, connectivity, holes, edge count)
bool is_valid_body(uint32_t cells, std::string* why = nullptr);
// true when `springs` has only its 21 low bits and at least one of them set
bool is_valid_springs(uint32_t springs, std::string* why = nullptr);
bool is_valid(const Body& b, std::string* why = nullptr);

// ---- enumeration ---------------------------------------------------------------------------------
// every valid 28-bit body in every placement, ascending (94 of them: a table checked against the enumeration below)
const std::vector<uint32_t>& all_valid_placements();
// the same by enumerating every 11-cell subset of the 28 cells (about 60 ms)
std::vector<uint32_t> enumerate_valid_placements();
// one placement per shape (see the header note), the lowest bit pattern of its class; ascending
std::vector<uint32_t> all_valid_bodies_up_to_translation();
// the representative (as above) of the shape of a valid placement
uint32_t shape_of(uint32_t cells);

// ---- random draws and mutation (every draw through common/rng.hpp) -------------------------------
// a uniformly random shape, then a uniformly random placement of it
uint32_t random_body(Rng& rng);
// the valid body nearest to `cells` in Hamming distance over all placements; ties are broken
// uniformly with rng (in ascending bit-pattern order). A valid body comes back unchanged and draws
// nothing. Bits above 28 are ignored.
uint32_t repair_body(uint32_t cells, Rng& rng);
// flips each of the 28 bits with probability p (one uniform draw per bit, bit 0 first), then repairs
uint32_t mutate_body(uint32_t cells, Rng& rng, double p = 1.0 / kCells);

// 21 independent fair bits; redrawn until at least one is set
uint32_t random_springs(Rng& rng);
// flips each of the 21 bits with probability p (one draw per bit, bit 0 first); if none is left
// active, one uniformly chosen bit is set
uint32_t mutate_springs(uint32_t springs, Rng& rng, double p = 1.0 / kBodyEdges);

// random_body, then random_springs
Body random_genotype(Rng& rng);

// ---- geometry ------------------------------------------------------------------------------------
// the lattice cells of an agent's masses: the set cells of `cells` in row-major (ascending) order
std::vector<int32_t> mass_cells(uint32_t cells);
// the bare agent of a valid body (SPEC §4.1): its genotypes, rest positions (the lattice points of
// mass_cells(cells) shifted so min x = 0, min y = 0), springs, rest lengths and amplitudes; no controller
// (params empty) and no anchors. Throws InputError on an invalid genotype
Agent agent_geometry(uint32_t cells, uint32_t springs);
inline Agent agent_geometry(const Body& b) { return agent_geometry(b.cells, b.springs); }

// ---- controller initialisation (SPEC §4.3) -------------------------------------------------------
// per layer, in the nn/mlp.hpp layout (W out × in row-major, then b): W ~ N(0, (g·sqrt(2/(in+out)))²)
// drawn in storage order with common/rng.hpp normal(), b = 0
inline constexpr std::array<double, 3> kAgentInitGains = {2.0, 2.0, 3.0};
// the spec gives no gains for the connector; it uses the agent's (2, 2, 3)
inline constexpr std::array<double, 3> kConnectorInitGains = {2.0, 2.0, 3.0};

// n_inputs → 32 → 32 → 21 (3509 values with 54 inputs)
std::vector<double> init_agent_params(Rng& rng, int n_inputs = 54);
// 11 → 32 → 32 → 1 (1473 values), or with joint the network that reads all five springs, 55 → 32 → 32 → 5 (3013)
// out_gain: the gain of the output layer (the first two keep 2, 2): a run's connectors.init_out_gain (the schema's
// default 0.1 starts the connector nearly passive); kConnectorInitGains[2] = 3, the agent's, for the random connectors
// of the scene, simulate and bench commands
std::vector<double> init_connector_params(Rng& rng, double out_gain, bool joint = false);

}  // namespace divcoll::morph
