// agent bodies (SPEC §4.1): see body.hpp
#include "morph/body.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <map>

#include "common/check.hpp"
#include "common/dmath.hpp"
#include "nn/mlp.hpp"

namespace divcoll::morph {
namespace {

constexpr int row_of(int cell) { return cell / kCols; }
constexpr int col_of(int cell) { return cell % kCols; }

// neighbour masks of all 28 cells, from the rule of §4.1
std::array<uint32_t, kCells> make_neighbours() {
  std::array<uint32_t, kCells> nb{};
  for (int i = 0; i < kCells; ++i) {
    const int r = row_of(i), c = col_of(i);
    auto add = [&](int rr, int cc) {
      if (rr >= 0 && rr < kRows && cc >= 0 && cc < kCols) nb[i] |= 1u << (rr * kCols + cc);
    };
    // same row c±1; rows r±1 at (c−1, c) for even r, (c, c+1) for odd r
    add(r, c - 1);
    add(r, c + 1);
    const int lo = (r % 2 == 0) ? c - 1 : c;
    for (int dr : {-1, 1}) {
      add(r + dr, lo);
      add(r + dr, lo + 1);
    }
  }
  return nb;
}

const std::array<uint32_t, kCells>& neighbours() {
  static const std::array<uint32_t, kCells> nb = make_neighbours();
  return nb;
}

// cells of the box that touch the outside (rows 0 and 3, columns 0 and 6)
constexpr uint32_t boundary_mask() {
  uint32_t m = 0;
  for (int i = 0; i < kCells; ++i) {
    const int r = row_of(i), c = col_of(i);
    if (r == 0 || r == kRows - 1 || c == 0 || c == kCols - 1) m |= 1u << i;
  }
  return m;
}

// the cells of `within` reachable from `seed` through lattice edges inside `within`
uint32_t flood(uint32_t seed, uint32_t within) {
  const auto& nb = neighbours();
  uint32_t reached = seed & within, frontier = reached;
  while (frontier) {
    uint32_t next = 0;
    for (uint32_t f = frontier; f; f &= f - 1) next |= nb[std::countr_zero(f)];
    next &= within & ~reached;
    reached |= next;
    frontier = next;
  }
  return reached;
}

// bit-parallel edge count for the enumeration: a cell i links forward to i+1 (same row), i+7 (row
// below, both parities), i+6 (even rows, column c−1) and i+8 (odd rows, column c+1)
struct EdgeMasks {
  uint32_t h = 0, v = 0, d6 = 0, d8 = 0;
};
constexpr EdgeMasks edge_masks() {
  EdgeMasks e;
  for (int i = 0; i < kCells; ++i) {
    const int r = row_of(i), c = col_of(i);
    if (c < kCols - 1) e.h |= 1u << i;
    if (r < kRows - 1) e.v |= 1u << i;
    if (r < kRows - 1 && r % 2 == 0 && c >= 1) e.d6 |= 1u << i;
    if (r < kRows - 1 && r % 2 == 1 && c < kCols - 1) e.d8 |= 1u << i;
  }
  return e;
}

int fast_edges(uint32_t m) {
  constexpr EdgeMasks e = edge_masks();
  return std::popcount(m & (m >> 1) & e.h) + std::popcount(m & (m >> 7) & e.v) +
         std::popcount(m & (m >> 6) & e.d6) + std::popcount(m & (m >> 8) & e.d8);
}

// translation key of a placement: cells as (2x/spacing, row) shifted to min 0, packed as a 4 × 14 bitmap
uint64_t translation_key(uint32_t cells) {
  int min_x = 1 << 20, min_r = 1 << 20;
  for (uint32_t m = cells; m; m &= m - 1) {
    const int i = std::countr_zero(m);
    min_x = std::min(min_x, 2 * col_of(i) + row_of(i) % 2);
    min_r = std::min(min_r, row_of(i));
  }
  uint64_t key = 0;
  for (uint32_t m = cells; m; m &= m - 1) {
    const int i = std::countr_zero(m);
    const int x = 2 * col_of(i) + row_of(i) % 2 - min_x, r = row_of(i) - min_r;
    key |= uint64_t{1} << (r * 2 * kCols + x);
  }
  return key;
}

// every valid placement, grouped by shape
struct Catalogue {
  std::vector<uint32_t> placements;                     // ascending
  std::vector<uint32_t> shapes;                         // representative per shape, ascending
  std::vector<std::vector<uint32_t>> shape_placements;  // per shape, ascending
  std::map<uint32_t, uint32_t> shape_of;                // placement -> representative
};

// every valid placement, ascending: what enumerate_valid_placements() finds among all C(28, 11) subsets (the
// body test compares the two). Enumerating took 60 ms, spent by the master at the start of every agents stage
// while the workers waited
constexpr uint32_t kValidPlacements[] = {
    0x003878f, 0x003879e, 0x003c78e, 0x0070f1e, 0x0070f3c, 0x007878e, 0x0078f1c, 0x00e1e3c,
    0x00e1e78, 0x00f0f1c, 0x00f1e38, 0x01c3c78, 0x01e1e38, 0x01e3c70, 0x043878e, 0x061c387,
    0x061c38e, 0x063c386, 0x083878e, 0x0870f1c, 0x0c38387, 0x0c3838e, 0x0c3870e, 0x0c3871c,
    0x0c38786, 0x0c3878c, 0x0c3c386, 0x0c7870c, 0x0e1c386, 0x0e38386, 0x0e3870c, 0x0e3c382,
    0x0e3c384, 0x0e3c780, 0x1070f1c, 0x10e1e38, 0x187070e, 0x187071c, 0x1870e1c, 0x1870e38,
    0x1870f0c, 0x1870f18, 0x187870c, 0x18f0e18, 0x1c38386, 0x1c3870c, 0x1c7070c, 0x1c70e18,
    0x1c78704, 0x1c78708, 0x1c78780, 0x1c78f00, 0x1e3c380, 0x1e78700, 0x20e1e38, 0x21c3c70,
    0x30e0e1c, 0x30e0e38, 0x30e1c38, 0x30e1c70, 0x30e1e18, 0x30e1e30, 0x30f0e18, 0x31e1c30,
    0x387070c, 0x3870e18, 0x38e0e18, 0x38e1c30, 0x38f0e08, 0x38f0e10, 0x38f0f00, 0x38f1e00,
    0x3c78700, 0x3cf0e00, 0x41c3c70, 0x61c1c38, 0x61c1c70, 0x61c3870, 0x61c3c30, 0x61c3c60,
    0x61e1c30, 0x70e0e18, 0x70e1c30, 0x71c1c30, 0x71c3860, 0x71e1c10, 0x71e1c20, 0x71e1e00,
    0x71e3c00, 0x78f0e00, 0x79e1c00, 0xe1c1c30, 0xe1c3860, 0xf1e1c00};

Catalogue build_catalogue() {
  Catalogue cat;
  cat.placements.assign(std::begin(kValidPlacements), std::end(kValidPlacements));
  for (uint32_t p : cat.placements) DIVCOLL_DEMAND(is_valid_body(p));
  // group by translation key; placements are visited ascending so the first of a class is its lowest
  std::map<uint64_t, size_t> by_key;
  for (uint32_t p : cat.placements) {
    const auto [it, fresh] = by_key.emplace(translation_key(p), cat.shape_placements.size());
    if (fresh) cat.shape_placements.emplace_back();
    cat.shape_placements[it->second].push_back(p);
  }
  // the lowest placements of the classes come in ascending order of class creation already
  for (const auto& ps : cat.shape_placements) {
    cat.shapes.push_back(ps.front());
    for (uint32_t p : ps) cat.shape_of[p] = ps.front();
  }
  return cat;
}

}  // namespace

std::vector<uint32_t> enumerate_valid_placements() {
  std::vector<uint32_t> out;
  // all C(28, 11) subsets in ascending order (Gosper's hack); the cheap edge count filters first
  const uint32_t last = kCellMask & ~((1u << (kCells - kBodyCells)) - 1);
  for (uint32_t v = (1u << kBodyCells) - 1;;) {
    if (fast_edges(v) == kBodyEdges && is_valid_body(v)) out.push_back(v);
    if (v == last) break;
    const uint32_t t = v | (v - 1);
    v = (t + 1) | (((~t & (t + 1)) - 1) >> (std::countr_zero(v) + 1));
  }
  return out;
}

namespace {

const Catalogue& catalogue() {
  static const Catalogue cat = build_catalogue();
  return cat;
}

}  // namespace

// ---- lattice -------------------------------------------------------------------------------------
std::array<double, 2> cell_position(int cell) {
  DIVCOLL_DEMAND(cell >= 0 && cell < kCells);
  const int r = row_of(cell), c = col_of(cell);
  return {kSpacing * c + 0.5 * kSpacing * (r % 2), kSpacing * r * std::sqrt(3.0) / 2.0};
}

uint32_t cell_neighbours(int cell) {
  DIVCOLL_DEMAND(cell >= 0 && cell < kCells);
  return neighbours()[cell];
}

int lattice_edges(uint32_t cells) {
  // each edge is seen from both ends
  int twice = 0;
  for (uint32_t m = cells & kCellMask; m; m &= m - 1)
    twice += std::popcount(neighbours()[std::countr_zero(m)] & cells);
  return twice / 2;
}

// ---- validity ------------------------------------------------------------------------------------
bool is_valid_body(uint32_t cells, std::string* why) {
  auto fail = [&](const std::string& reason) {
    if (why) *why = reason;
    return false;
  };
  if (cells & ~kCellMask) return fail(msg() << "body genotype has bits above the 28 lattice cells");
  const int n = std::popcount(cells);
  if (n != kBodyCells) return fail(msg() << "body has " << n << " cells, needs " << kBodyCells);
  // connected: a flood from the lowest set cell reaches every set cell
  if (flood(cells & (~cells + 1), cells) != cells) return fail(msg() << "body cells are not connected");
  // holes: flood the empty cells from the box boundary; an empty cell not reached is enclosed
  const uint32_t empty = kCellMask & ~cells;
  const uint32_t enclosed = empty & ~flood(boundary_mask() & empty, empty);
  if (enclosed) {
    const int i = std::countr_zero(enclosed);
    return fail(msg() << "body has an enclosed hole at cell (" << row_of(i) << ", " << col_of(i) << ")");
  }
  const int e = lattice_edges(cells);
  if (e != kBodyEdges) return fail(msg() << "body has " << e << " lattice edges, needs " << kBodyEdges);
  return true;
}

bool is_valid_springs(uint32_t springs, std::string* why) {
  auto fail = [&](const std::string& reason) {
    if (why) *why = reason;
    return false;
  };
  if (springs & ~kSpringMask) return fail(msg() << "spring genotype has bits above the 21 springs");
  if (springs == 0) return fail(msg() << "spring genotype has no active spring");
  return true;
}

bool is_valid(const Body& b, std::string* why) {
  return is_valid_body(b.cells, why) && is_valid_springs(b.springs, why);
}

// ---- enumeration ---------------------------------------------------------------------------------
const std::vector<uint32_t>& all_valid_placements() { return catalogue().placements; }

std::vector<uint32_t> all_valid_bodies_up_to_translation() { return catalogue().shapes; }

uint32_t shape_of(uint32_t cells) {
  const auto& m = catalogue().shape_of;
  const auto it = m.find(cells);
  DIVCOLL_THROW_UNLESS(it != m.end(), "shape_of: 0x" << std::hex << cells << " is not a valid body");
  return it->second;
}

// ---- random draws and mutation -------------------------------------------------------------------
uint32_t random_body(Rng& rng) {
  const auto& cat = catalogue();
  const auto& ps = cat.shape_placements[uniform_int(rng, cat.shape_placements.size())];
  return ps[uniform_int(rng, ps.size())];
}

uint32_t repair_body(uint32_t cells, Rng& rng) {
  cells &= kCellMask;
  if (is_valid_body(cells)) return cells;
  // the nearest placements in Hamming distance, ascending
  std::vector<uint32_t> nearest;
  int best = kCells + 1;
  for (uint32_t p : all_valid_placements()) {
    const int d = std::popcount(p ^ cells);
    if (d < best) {
      best = d;
      nearest.clear();
    }
    if (d == best) nearest.push_back(p);
  }
  return nearest.size() == 1 ? nearest.front() : nearest[uniform_int(rng, nearest.size())];
}

uint32_t mutate_body(uint32_t cells, Rng& rng, double p) {
  for (int i = 0; i < kCells; ++i)
    if (uniform01(rng) < p) cells ^= 1u << i;
  return repair_body(cells, rng);
}

uint32_t random_springs(Rng& rng) {
  for (;;) {
    const uint32_t s = static_cast<uint32_t>(rng()) & kSpringMask;
    if (s) return s;
  }
}

uint32_t mutate_springs(uint32_t springs, Rng& rng, double p) {
  springs &= kSpringMask;
  for (int i = 0; i < kBodyEdges; ++i)
    if (uniform01(rng) < p) springs ^= 1u << i;
  if (springs == 0) springs = 1u << uniform_int(rng, kBodyEdges);
  return springs;
}

Body random_genotype(Rng& rng) {
  Body b;
  b.cells = random_body(rng);
  b.springs = random_springs(rng);
  return b;
}

// ---- geometry ------------------------------------------------------------------------------------
int Agent::n_active() const {
  return static_cast<int>(std::count_if(amplitude.begin(), amplitude.end(), [](double a) { return a != 0; }));
}

double body_length(const Agent& a) {
  double lo = a.rest_pos[0], hi = a.rest_pos[0];
  for (int q = 0; q < kBodyCells; ++q) lo = std::min(lo, a.rest_pos[2 * q]), hi = std::max(hi, a.rest_pos[2 * q]);
  return hi - lo;
}

void update_rest_lengths(Agent& a) {
  a.rest_length.resize(a.spring_i.size());
  for (size_t s = 0; s < a.spring_i.size(); ++s) {
    const int i = a.spring_i[s], j = a.spring_j[s];
    a.rest_length[s] =
        dmath::hypot(a.rest_pos[2 * j] - a.rest_pos[2 * i], a.rest_pos[2 * j + 1] - a.rest_pos[2 * i + 1]);
  }
}

std::vector<int32_t> mass_cells(uint32_t cells) {
  std::vector<int32_t> cell;
  for (uint32_t m = cells; m; m &= m - 1) cell.push_back(std::countr_zero(m));
  return cell;
}

Agent agent_geometry(uint32_t cells, uint32_t springs) {
  std::string why;
  DIVCOLL_THROW_UNLESS(is_valid_body(cells, &why), "agent_geometry: " << why);
  DIVCOLL_THROW_UNLESS(is_valid_springs(springs, &why), "agent_geometry: " << why);
  Agent g;
  g.cells = cells;
  g.springs = springs;
  // masses: set cells in row-major order, at their lattice points
  const std::vector<int32_t> cell = mass_cells(cells);
  double min_x = 1e300, min_y = 1e300;
  for (int c : cell) {
    const auto p = cell_position(c);
    g.rest_pos.push_back(p[0]);
    g.rest_pos.push_back(p[1]);
    min_x = std::min(min_x, p[0]);
    min_y = std::min(min_y, p[1]);
  }
  // shift so min x = min y = 0
  for (int k = 0; k < kBodyCells; ++k) {
    g.rest_pos[2 * k] -= min_x;
    g.rest_pos[2 * k + 1] -= min_y;
  }
  // springs: lattice edges between masses, sorted pairs (i < j)
  for (int i = 0; i < kBodyCells; ++i)
    for (int j = i + 1; j < kBodyCells; ++j)
      if (cell_neighbours(cell[i]) & (1u << cell[j])) {
        const int s = static_cast<int>(g.spring_i.size());
        g.spring_i.push_back(i);
        g.spring_j.push_back(j);
        g.amplitude.push_back((springs >> s) & 1u ? kActiveAmplitude : 0.0);
      }
  DIVCOLL_DEMAND(g.spring_i.size() == kBodyEdges);
  update_rest_lengths(g);
  return g;
}

// ---- controller initialisation -------------------------------------------------------------------
namespace {
std::vector<double> init_mlp(const nn::Layout& L, const std::array<double, 3>& gains, Rng& rng) {
  DIVCOLL_DEMAND(L.n_layers() == static_cast<int>(gains.size()));
  std::vector<double> p(L.param_count(), 0.0);
  for (int l = 0; l < L.n_layers(); ++l) {
    const int in = L.sizes[l], out = L.sizes[l + 1];
    const double sd = gains[l] * std::sqrt(2.0 / (in + out));
    double* w = p.data() + L.weight_offset(l);
    for (int k = 0; k < in * out; ++k) w[k] = sd * normal(rng);
  }
  return p;
}
}  // namespace

std::vector<double> init_agent_params(Rng& rng, int n_inputs) {
  DIVCOLL_THROW_UNLESS(n_inputs > 0, "init_agent_params: n_inputs must be positive, got " << n_inputs);
  return init_mlp(nn::agent_layout(n_inputs), kAgentInitGains, rng);
}

std::vector<double> init_connector_params(Rng& rng, double out_gain, bool joint) {
  return init_mlp(joint ? nn::joint_connector_layout() : nn::connector_layout(),
                  {kConnectorInitGains[0], kConnectorInitGains[1], out_gain}, rng);
}

}  // namespace divcoll::morph
