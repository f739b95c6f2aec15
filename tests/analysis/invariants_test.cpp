// Place and transition invariants: known bases on hand-made nets, and seeded random matrices
// checked against the definition and against a brute-force enumeration of small solutions.
#include <catch2/catch.hpp>

#include <random>

#include "analysis_test_nets.hpp"
#include "tripodal/analysis/invariants.hpp"

using namespace tripodal;
using namespace tripodal::analysis;

namespace {

using Weights = std::vector<std::pair<std::uint32_t, std::int64_t>>;

Weights named(const PetriNet& net, std::initializer_list<std::pair<const char*, std::int64_t>> items, bool places) {
  Weights w;
  for (const auto& [id, k] : items) {
    w.emplace_back(places ? *net.find_place(id) : *net.find_transition(id), k);
  }
  std::sort(w.begin(), w.end());
  return w;
}

bool contains(const InvariantBasis& b, const Weights& w) {
  return std::any_of(b.invariants.begin(), b.invariants.end(), [&](const Invariant& i) { return i.weights == w; });
}

}  // namespace

TEST_CASE("Kanban: one place invariant per stage, and two across the synchronised stages 2 and 3", "[analysis][invariants]") {
  const PetriNet net = test::kanban_net(2);
  const InvariantBasis p = place_invariants(net);
  CHECK(p.complete);
  REQUIRE(p.invariants.size() == 6);
  // tsynch4_23 moves a kanban from P2 to Pm2 and one from P3 to Pm3 at once, tsynch1_23 returns
  // both: P2 and P3 stand in for each other in the stage invariants.
  CHECK(contains(p, named(net, {{"P2", 1}, {"Pm3", 1}, {"Pback3", 1}, {"Pout3", 1}}, true)));
  CHECK(contains(p, named(net, {{"P3", 1}, {"Pm2", 1}, {"Pback2", 1}, {"Pout2", 1}}, true)));
  for (int i = 1; i <= 4; ++i) {
    const std::string s = std::to_string(i);
    const Weights w = named(net, {{("P" + s).c_str(), 1}, {("Pm" + s).c_str(), 1}, {("Pback" + s).c_str(), 1},
                                  {("Pout" + s).c_str(), 1}}, true);
    CHECK(contains(p, w));
  }
  for (const Invariant& inv : p.invariants) CHECK(inv.token_sum == 2);
  for (const auto c : p.covered) CHECK(c == 1);
  const auto bounds = structural_bounds(net, p);
  for (const auto& b : bounds) CHECK(b == Tokens{2});

  const InvariantBasis t = transition_invariants(net);
  CHECK(t.complete);
  // redo/back loops of each stage, and the production cycle.
  for (int i = 1; i <= 4; ++i) {
    const std::string s = std::to_string(i);
    CHECK(contains(t, named(net, {{("tredo" + s).c_str(), 1}, {("tback" + s).c_str(), 1}}, false)));
  }
  CHECK(contains(t, named(net, {{"tin4", 1}, {"tok4", 1}, {"tsynch4_23", 1}, {"tok2", 1}, {"tok3", 1},
                                {"tsynch1_23", 1}, {"tok1", 1}, {"tout1", 1}}, false)));
  CHECK(t.invariants.size() == 5);
}

TEST_CASE("Weighted arcs give weighted invariants, read arcs change nothing", "[analysis][invariants]") {
  // t: 2 a -> b, u: b -> 2 a; a reads c.
  PetriNet net;
  net.add_place(Place{.id = "a", .initial_tokens = 4});
  net.add_place(Place{.id = "b"});
  net.add_place(Place{.id = "c", .initial_tokens = 1});
  net.add_place(Place{.id = "sink"});
  net.add_transition(Transition{.id = "t"});
  net.add_transition(Transition{.id = "u"});
  net.add_transition(Transition{.id = "v"});
  net.add_arc("a", "t", 2);
  net.add_arc("t", "b");
  net.add_arc("b", "u");
  net.add_arc("u", "a", 2);
  net.add_arc("c", "t", 1, ArcKind::read);
  net.add_arc("sink", "v", 1, ArcKind::inhibitor);
  net.add_arc("v", "sink");
  const InvariantBasis p = place_invariants(net);
  REQUIRE(p.invariants.size() == 2);
  CHECK(contains(p, named(net, {{"a", 1}, {"b", 2}}, true)));
  CHECK(contains(p, named(net, {{"c", 1}}, true)));
  CHECK(p.covered[*net.find_place("sink")] == 0);
  const InvariantBasis t = transition_invariants(net);
  REQUIRE(t.invariants.size() == 1);
  CHECK(contains(t, named(net, {{"t", 1}, {"u", 1}}, false)));
}

TEST_CASE("A net without conservation has no place invariant", "[analysis][invariants]") {
  PetriNet net;
  net.add_place(Place{.id = "p", .initial_tokens = 1});
  net.add_transition(Transition{.id = "grow"});
  net.add_arc("p", "grow");
  net.add_arc("grow", "p", 2);
  CHECK(place_invariants(net).invariants.empty());
  CHECK(transition_invariants(net).invariants.empty());
}

TEST_CASE("Random matrices: the basis matches the definition and a brute-force enumeration", "[analysis][invariants][random]") {
  std::mt19937 rng(20261122);
  std::uniform_int_distribution<int> entry(-2, 2);
  std::uniform_int_distribution<int> zero(0, 2);
  for (int round = 0; round < 300; ++round) {
    const std::size_t n = 2 + static_cast<std::size_t>(round % 4);  // unknowns
    const std::size_t m = 1 + static_cast<std::size_t>((round / 4) % 4);
    std::vector<std::vector<std::int64_t>> a(n, std::vector<std::int64_t>(m));
    for (auto& row : a) {
      for (auto& v : row) v = zero(rng) == 0 ? entry(rng) : 0;
    }
    const InvariantBasis basis = semi_positive_kernel(a);
    REQUIRE(basis.complete);
    std::vector<std::vector<std::uint64_t>> supports;
    for (const Invariant& inv : basis.invariants) {
      std::vector<std::int64_t> y(n, 0);
      for (const auto& [i, w] : inv.weights) {
        REQUIRE(w > 0);
        y[i] = w;
      }
      for (std::size_t j = 0; j < m; ++j) {
        std::int64_t sum = 0;
        for (std::size_t i = 0; i < n; ++i) sum += y[i] * a[i][j];
        REQUIRE(sum == 0);
      }
      std::uint64_t s = 0;
      for (const auto& [i, w] : inv.weights) s |= std::uint64_t{1} << i;
      supports.push_back({s});
    }
    // Every solution y in {0..3}^n, y != 0, has a support that is a union of basis supports,
    // and no basis support strictly contains the support of a brute-force solution.
    std::vector<std::int64_t> y(n, 0);
    for (;;) {
      std::size_t k = 0;
      while (k < n && y[k] == 3) y[k++] = 0;
      if (k == n) break;
      ++y[k];
      bool solution = true;
      for (std::size_t j = 0; j < m && solution; ++j) {
        std::int64_t sum = 0;
        for (std::size_t i = 0; i < n; ++i) sum += y[i] * a[i][j];
        solution = sum == 0;
      }
      if (!solution) continue;
      std::uint64_t s = 0;
      for (std::size_t i = 0; i < n; ++i) s |= y[i] != 0 ? std::uint64_t{1} << i : 0;
      std::uint64_t covered = 0;
      for (const auto& b : supports) {
        if ((b[0] & ~s) == 0) covered |= b[0];
        INFO("round " << round);
        REQUIRE_FALSE(((s & ~b[0]) == 0 && s != b[0]));  // a basis support must be minimal
      }
      INFO("round " << round);
      REQUIRE(covered == s);
    }
  }
}
