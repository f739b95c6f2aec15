// Farkas' algorithm: start from [A | I] (one row per unknown), eliminate the columns of A one by
// one by adding positive multiples of row pairs with opposite signs in that column, and keep
// only rows whose support (the identity part) is minimal. The surviving identity parts are the
// minimal-support semi-positive solutions. Columns are eliminated in the order that creates the
// fewest new rows first, which keeps the intermediate matrices small on nets like Kanban.
#include "tripodal/analysis/invariants.hpp"

#include <algorithm>
#include <limits>
#include <numeric>

namespace tripodal::analysis {

namespace {

struct Row {
  std::vector<std::int64_t> a;     // remaining columns of A
  std::vector<std::int64_t> y;     // coefficients of the unknowns
  std::vector<std::uint64_t> support;
};

std::vector<std::uint64_t> support_of(const std::vector<std::int64_t>& y) {
  std::vector<std::uint64_t> s((y.size() + 63) / 64, 0);
  for (std::size_t i = 0; i < y.size(); ++i) {
    if (y[i] != 0) s[i / 64] |= std::uint64_t{1} << (i % 64);
  }
  return s;
}

bool subset(const std::vector<std::uint64_t>& a, const std::vector<std::uint64_t>& b) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    if ((a[i] & ~b[i]) != 0) return false;
  }
  return true;
}

// Divides a row by the gcd of its entries.
void normalise(Row& r) {
  std::int64_t g = 0;
  for (const auto v : r.a) g = std::gcd(g, v < 0 ? -v : v);
  for (const auto v : r.y) g = std::gcd(g, v);
  if (g > 1) {
    for (auto& v : r.a) v /= g;
    for (auto& v : r.y) v /= g;
  }
}

// ca * x + cb * z with overflow detection.
bool combine(std::int64_t ca, std::int64_t x, std::int64_t cb, std::int64_t z, std::int64_t& out) {
  std::int64_t p = 0;
  std::int64_t q = 0;
  if (__builtin_mul_overflow(ca, x, &p) || __builtin_mul_overflow(cb, z, &q) || __builtin_add_overflow(p, q, &out)) {
    return false;
  }
  return true;
}

}  // namespace

IncidenceMatrix incidence_matrix(const PetriNet& net) {
  IncidenceMatrix c(net.places().size(), std::vector<std::int64_t>(net.transitions().size(), 0));
  for (TransitionIndex t = 0; t < net.transitions().size(); ++t) {
    const Transition& tr = net.transition(t);
    for (const ArcRef& a : tr.inputs) c[a.place][t] -= a.weight;
    for (const ArcRef& a : tr.outputs) c[a.place][t] += a.weight;
  }
  return c;
}

InvariantBasis semi_positive_kernel(const std::vector<std::vector<std::int64_t>>& a, const InvariantOptions& options) {
  InvariantBasis basis;
  const std::size_t n = a.size();
  const std::size_t m = n == 0 ? 0 : a[0].size();
  basis.covered.assign(n, 0);
  std::vector<Row> rows;
  rows.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    Row r;
    r.a = a[i];
    r.y.assign(n, 0);
    r.y[i] = 1;
    r.support = support_of(r.y);
    rows.push_back(std::move(r));
  }
  std::vector<std::uint8_t> done(m, 0);
  for (std::size_t step = 0; step < m; ++step) {
    // The column whose elimination adds the fewest rows (pos * neg - pos - neg).
    std::size_t col = m;
    long long best = std::numeric_limits<long long>::max();
    for (std::size_t j = 0; j < m; ++j) {
      if (done[j] != 0) continue;
      long long pos = 0;
      long long neg = 0;
      for (const Row& r : rows) {
        pos += r.a[j] > 0 ? 1 : 0;
        neg += r.a[j] < 0 ? 1 : 0;
      }
      const long long cost = pos * neg - pos - neg;
      if (cost < best) {
        best = cost;
        col = j;
      }
    }
    done[col] = 1;
    std::vector<Row> next;
    std::vector<const Row*> pos;
    std::vector<const Row*> neg;
    for (Row& r : rows) {
      if (r.a[col] == 0) {
        next.push_back(std::move(r));
      } else {
        (r.a[col] > 0 ? pos : neg).push_back(&r);
      }
    }
    const std::size_t kept = next.size();
    for (const Row* p : pos) {
      for (const Row* q : neg) {
        // Minimal support candidates only: a combination whose support contains another kept
        // row's is pruned below; skip exact duplicates of supports early.
        Row r;
        const std::int64_t cp = -q->a[col];
        const std::int64_t cq = p->a[col];
        r.a.resize(m);
        r.y.resize(n);
        bool ok = true;
        for (std::size_t j = 0; j < m && ok; ++j) ok = combine(cp, p->a[j], cq, q->a[j], r.a[j]);
        for (std::size_t i = 0; i < n && ok; ++i) ok = combine(cp, p->y[i], cq, q->y[i], r.y[i]);
        if (!ok) {
          basis.complete = false;
          continue;
        }
        r.a[col] = 0;
        normalise(r);
        r.support.resize(p->support.size());
        for (std::size_t w = 0; w < r.support.size(); ++w) r.support[w] = p->support[w] | q->support[w];
        next.push_back(std::move(r));
        if (next.size() > options.max_rows) break;
      }
      if (next.size() > options.max_rows) break;
    }
    if (next.size() > options.max_rows) {
      basis.complete = false;
      next.resize(kept);  // keep what is certainly still useful; the rest cannot be finished
    }
    // Minimal-support pruning: drop a row whose support contains another row's (ties: keep the
    // first). Rows without a nonzero left in A do not matter for the containment test.
    std::vector<std::uint8_t> drop(next.size(), 0);
    for (std::size_t i = kept; i < next.size(); ++i) {
      for (std::size_t k = 0; k < next.size() && drop[i] == 0; ++k) {
        if (k == i || drop[k] != 0) continue;
        if (subset(next[k].support, next[i].support) && (next[k].support != next[i].support || k < i)) drop[i] = 1;
      }
    }
    rows.clear();
    for (std::size_t i = 0; i < next.size(); ++i) {
      if (drop[i] == 0) rows.push_back(std::move(next[i]));
    }
  }
  for (const Row& r : rows) {
    Invariant inv;
    for (std::size_t i = 0; i < n; ++i) {
      if (r.y[i] != 0) {
        inv.weights.emplace_back(static_cast<std::uint32_t>(i), r.y[i]);
        basis.covered[i] = 1;
      }
    }
    if (!inv.weights.empty()) basis.invariants.push_back(std::move(inv));
  }
  std::sort(basis.invariants.begin(), basis.invariants.end(),
            [](const Invariant& x, const Invariant& y) { return x.weights < y.weights; });
  return basis;
}

InvariantBasis place_invariants(const PetriNet& net, const InvariantOptions& options) {
  InvariantBasis basis = semi_positive_kernel(incidence_matrix(net), options);
  const Marking m0 = net.initial_marking();
  for (Invariant& inv : basis.invariants) {
    for (const auto& [p, w] : inv.weights) inv.token_sum += w * static_cast<std::int64_t>(m0[p]);
  }
  return basis;
}

InvariantBasis transition_invariants(const PetriNet& net, const InvariantOptions& options) {
  const IncidenceMatrix c = incidence_matrix(net);
  std::vector<std::vector<std::int64_t>> ct(net.transitions().size(), std::vector<std::int64_t>(c.size(), 0));
  for (std::size_t p = 0; p < c.size(); ++p) {
    for (std::size_t t = 0; t < c[p].size(); ++t) ct[t][p] = c[p][t];
  }
  return semi_positive_kernel(ct, options);
}

std::vector<std::optional<Tokens>> structural_bounds(const PetriNet& net, const InvariantBasis& p_invariants) {
  std::vector<std::optional<Tokens>> bounds(net.places().size());
  for (const Invariant& inv : p_invariants.invariants) {
    for (const auto& [p, w] : inv.weights) {
      const std::int64_t b = inv.token_sum / w;
      if (b > std::numeric_limits<Tokens>::max()) continue;
      if (!bounds[p] || static_cast<Tokens>(b) < *bounds[p]) bounds[p] = static_cast<Tokens>(b);
    }
  }
  return bounds;
}

}  // namespace tripodal::analysis
