// The balloon's rounds (paper, section 3.2): the boundary of an offset region walked as cell
// chains, pieces joined where their ends meet, and a closed round inserted where the tour
// passes by it; the balloon pattern itself.
#include <algorithm>
#include <cmath>
#include <limits>

#include "coverage_internal.hpp"
#include "tripodal/navi/coverage.hpp"

namespace tripodal::navi {

using coverage_detail::dist2;

std::optional<std::vector<CoveragePlanner::RoundPiece>> CoveragePlanner::round_pieces(Workspace& ws,
                                                                                      const std::vector<std::uint8_t>& in_round,
                                                                                      CellIndex cur) const {
  const std::size_t n = ws.offset.size();
  std::vector<std::uint8_t> boundary(n, 0), used(n, 0), near(n, 0);
  std::vector<std::size_t> boundary_cells;
  for (int ly = 0; ly < ws.h; ++ly) {
    for (int lx = 0; lx < ws.w; ++lx) {
      const std::size_t li = ws.local(lx, ly);
      if (in_round[li] == 0) continue;
      const int nx[4] = {lx + 1, lx - 1, lx, lx};
      const int ny[4] = {ly, ly, ly + 1, ly - 1};
      for (int q = 0; q < 4; ++q) {
        if (!ws.inside(nx[q], ny[q]) || in_round[ws.local(nx[q], ny[q])] == 0) {
          boundary[li] = 1;
          boundary_cells.push_back(li);
          break;
        }
      }
    }
  }
  if (boundary_cells.empty()) return std::nullopt;
  std::vector<RoundPiece> pieces;
  std::vector<CellIndex> chain;
  for (;;) {
    // the nearest boundary cell not yet walked or beside a walked one
    std::size_t seed = n;
    long long seed_d = std::numeric_limits<long long>::max();
    for (const std::size_t li : boundary_cells) {
      if (used[li] != 0 || near[li] != 0) continue;
      const int lx = static_cast<int>(li % static_cast<std::size_t>(ws.w));
      const int ly = static_cast<int>(li / static_cast<std::size_t>(ws.w));
      const CellIndex g = ws.global(lx, ly);
      const long long d =
          cur.x < 0 ? static_cast<long long>(li) : 1LL * (g.x - cur.x) * (g.x - cur.x) + 1LL * (g.y - cur.y) * (g.y - cur.y);
      if (d < seed_d) {
        seed_d = d;
        seed = li;
      }
    }
    if (seed == n) break;
    walk_chain(ws, boundary, used, near, seed, chain);
    if (chain.size() < 3) continue;  // specks: the touch-up visits them if they matter
    const CellIndex first = chain.front();
    const CellIndex last = chain.back();
    // closed when the last cell steps back onto the first as A* could (not across a corner)
    const bool closed = chain.size() > 4 && std::abs(first.x - last.x) <= 1 && std::abs(first.y - last.y) <= 1 &&
                        (first.x == last.x || first.y == last.y ||
                         (planner_.traversable({first.x, last.y}) && planner_.traversable({last.x, first.y})));
    pieces.push_back({chain, closed});
    cur = closed ? first : last;
  }
  return pieces;
}

void CoveragePlanner::walk_chain(const Workspace& ws, const std::vector<std::uint8_t>& boundary, std::vector<std::uint8_t>& used,
                                 std::vector<std::uint8_t>& near, std::size_t seed, std::vector<CellIndex>& chain) const {
  // from the seed, keeping the heading where possible
  chain.clear();
  int lx = static_cast<int>(seed % static_cast<std::size_t>(ws.w));
  int ly = static_cast<int>(seed / static_cast<std::size_t>(ws.w));
  int hx = 0, hy = 0;
  for (;;) {
    const std::size_t li = ws.local(lx, ly);
    used[li] = 1;
    chain.push_back(ws.global(lx, ly));
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (ws.inside(lx + dx, ly + dy)) near[ws.local(lx + dx, ly + dy)] = 1;
      }
    }
    int best_dx = 0, best_dy = 0;
    double best_cost = std::numeric_limits<double>::infinity();
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || !ws.inside(lx + dx, ly + dy)) continue;
        const std::size_t k2 = ws.local(lx + dx, ly + dy);
        if (boundary[k2] == 0 || used[k2] != 0) continue;
        // as A* does: a diagonal step may not cut the corner of an inflated obstacle
        if (dx != 0 && dy != 0 &&
            (!planner_.traversable(ws.global(lx + dx, ly)) || !planner_.traversable(ws.global(lx, ly + dy)))) {
          continue;
        }
        double cost = 0.0;
        if (hx != 0 || hy != 0) {
          const double dot = (dx * hx + dy * hy) / (std::hypot(dx, dy) * std::hypot(hx, hy));
          cost = std::acos(std::clamp(dot, -1.0, 1.0));
        }
        if (dx != 0 && dy != 0) cost += 1e-3;  // on a tie, the side step
        if (cost < best_cost) {
          best_cost = cost;
          best_dx = dx;
          best_dy = dy;
        }
      }
    }
    if (!std::isfinite(best_cost) || best_cost > 2.0) break;  // dead end or a turn back
    hx = best_dx;
    hy = best_dy;
    lx += best_dx;
    ly += best_dy;
  }
}

void CoveragePlanner::append_piece(CoverageResult& r, CellIndex& cur, const RoundPiece& piece, std::optional<Point2D> start) {
  const CellIndex first = piece.cells.front();
  std::vector<Point2D> pts;
  for (const CellIndex& c : piece.cells) pts.push_back(grid_.cell_center(c));
  if (piece.closed) pts.push_back(grid_.cell_center(first));
  if (r.path.empty()) {
    if (start) {
      r.path.push_back(*start);
      if (cur.x >= 0 && grid_.contains(cur) && planner_.traversable(cur)) link(r.path, cur, first);
    }
  } else {
    link(r.path, cur, first);
  }
  std::size_t from = 0;
  if (!r.path.empty() && std::hypot(r.path.back().x_m - pts.front().x_m, r.path.back().y_m - pts.front().y_m) < 1e-9) {
    from = 1;
  }
  r.path.insert(r.path.end(), pts.begin() + static_cast<std::ptrdiff_t>(from), pts.end());
  cur = piece.closed ? first : piece.cells.back();
  ++r.passes;
}

CoverageResult CoveragePlanner::balloon(const Section& section, std::optional<Point2D> start) {
  CoverageResult r;
  Workspace ws = prepare(section);
  if (ws.stand_cells_global.empty()) {
    finish(r, ws, {0, 0});
    return r;
  }
  const double spacing = std::max(grid_.resolution_m(), options_.cleaning_width_m - options_.overlap_m);
  const std::size_t n = ws.offset.size();
  std::vector<std::uint8_t> in_round(n);
  CellIndex cur = start_cell(start);
  // The last, "ridge" round: where the offsets of both sides meet (the medial axis of the
  // section), a strip narrower than the spacing stays unswept; its outline is walked once.
  bool ridge = false;
  for (std::size_t k = 0;; ++k) {
    const float level = static_cast<float>(static_cast<double>(k) * spacing);
    if (!ridge) {
      for (std::size_t li = 0; li < n; ++li) in_round[li] = ws.stand[li] != 0 && ws.offset[li] >= level ? 1 : 0;
    } else {
      CleanedCells swept(grid_);
      swept.mark_path(r.path, options_.cleaning_width_m / 2.0);
      for (int ly = 0; ly < ws.h; ++ly) {
        for (int lx = 0; lx < ws.w; ++lx) {
          const std::size_t li = ws.local(lx, ly);
          in_round[li] = ws.stand[li] != 0 && !swept.cleaned(ws.global(lx, ly)) ? 1 : 0;
        }
      }
    }
    const auto pieces = round_pieces(ws, in_round, cur);
    if (!pieces) {
      if (ridge) break;
      ridge = true;
      continue;
    }
    for (const RoundPiece& piece : *pieces) append_piece(r, cur, piece, start);
    ++r.rounds;
    if (ridge) break;
  }
  finish(r, ws, cur);
  return r;
}

void CoveragePlanner::join_pieces(std::vector<RoundPiece>& pieces) {
  // round_pieces breaks a chain where it would turn by more than a right angle, so the round
  // around a box comes as its four sides. Ends a few cells apart with a clear line between them
  // are one walk: sides joined at the corners, and a chain whose ends meet is closed.
  constexpr int kGap = 6;          // cells, Chebyshev: around the corner of a box, a quarter of a pillar
  std::vector<CellIndex> between;  // the cells that join two ends, when they are near
  const auto near = [&](CellIndex a, CellIndex b) {
    between.clear();
    if (std::abs(a.x - b.x) > kGap || std::abs(a.y - b.y) > kGap) return false;
    if (planner_.line_of_sight(a, b)) return true;
    return local_path(a, b, kGap, between);
  };
  for (bool merged = true; merged;) {
    merged = false;
    for (std::size_t i = 0; i < pieces.size() && !merged; ++i) {
      if (pieces[i].closed) continue;
      for (std::size_t j = i + 1; j < pieces.size() && !merged; ++j) {
        if (pieces[j].closed) continue;
        auto& a = pieces[i].cells;
        auto b = pieces[j].cells;
        if (near(a.back(), b.back()) || near(a.front(), b.front())) std::reverse(b.begin(), b.end());
        if (near(a.back(), b.front())) {
          a.insert(a.end(), between.begin(), between.end());
          a.insert(a.end(), b.begin(), b.end());
        } else if (near(b.back(), a.front())) {
          b.insert(b.end(), between.begin(), between.end());
          b.insert(b.end(), a.begin(), a.end());
          a = std::move(b);
        } else {
          continue;
        }
        pieces.erase(pieces.begin() + static_cast<std::ptrdiff_t>(j));
        merged = true;
      }
    }
  }
  for (RoundPiece& p : pieces) {
    if (!p.closed && p.cells.size() > std::size_t{2} * kGap && near(p.cells.back(), p.cells.front())) {
      p.cells.insert(p.cells.end(), between.begin(), between.end());
      p.closed = true;
    }
  }
}

bool CoveragePlanner::local_path(CellIndex a, CellIndex b, int margin, std::vector<CellIndex>& between) const {
  // Breadth-first over the traversable cells of the box around a and b (8-connected, a diagonal
  // never cutting a corner, as A* moves): the planner's A* would search the whole map before
  // failing for ends that a wall separates.
  const int x0 = std::min(a.x, b.x) - margin, y0 = std::min(a.y, b.y) - margin;
  const int w = std::abs(a.x - b.x) + 2 * margin + 1, h = std::abs(a.y - b.y) + 2 * margin + 1;
  const auto index = [&](CellIndex c) {
    return static_cast<std::size_t>(c.y - y0) * static_cast<std::size_t>(w) + static_cast<std::size_t>(c.x - x0);
  };
  const auto open = [&](CellIndex c) {
    return c.x >= x0 && c.y >= y0 && c.x < x0 + w && c.y < y0 + h && grid_.contains(c) && planner_.traversable(c);
  };
  std::vector<int> from(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), -1);
  std::vector<CellIndex> queue{a};
  from[index(a)] = static_cast<int>(index(a));
  for (std::size_t q = 0; q < queue.size(); ++q) {
    const CellIndex c = queue[q];
    if (c == b) break;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const CellIndex n{c.x + dx, c.y + dy};
        if ((dx == 0 && dy == 0) || !open(n) || from[index(n)] >= 0) continue;
        if (dx != 0 && dy != 0 && (!open({c.x + dx, c.y}) || !open({c.x, c.y + dy}))) continue;
        from[index(n)] = static_cast<int>(index(c));
        queue.push_back(n);
      }
    }
  }
  if (!open(b) || from[index(b)] < 0) return false;
  between.clear();
  for (std::size_t i = static_cast<std::size_t>(from[index(b)]); i != index(a); i = static_cast<std::size_t>(from[i])) {
    between.push_back({x0 + static_cast<int>(i) % w, y0 + static_cast<int>(i) / w});
  }
  std::reverse(between.begin(), between.end());
  return between.size() <= 2 * static_cast<std::size_t>(margin);
}

void CoveragePlanner::insert_round(CoverageResult& r, CellIndex& cur, const RoundPiece& piece, std::size_t tour_begin,
                                   std::optional<Point2D> start) {
  // The cheapest place: a point S of a leg of the tour (a lane passing by, usually) from which
  // the round is entered at its nearest cell and left again at S: 2 |S c| of travel added. The
  // other choice is after the tour's end, |end c|, with no way back.
  const auto& path = r.path;
  std::vector<Point2D> centres;
  centres.reserve(piece.cells.size());
  for (const CellIndex& c : piece.cells) centres.push_back(grid_.cell_center(c));
  double best2 = std::numeric_limits<double>::infinity();  // |S c|^2
  std::size_t best_leg = 0, best_cell = 0;
  CellIndex split{};
  for (std::size_t k = tour_begin; k + 1 < path.size(); ++k) {
    const Point2D a = path[k], b = path[k + 1];
    const double dx = b.x_m - a.x_m, dy = b.y_m - a.y_m, len2 = dx * dx + dy * dy;
    for (std::size_t i = 0; i < centres.size(); ++i) {
      const Point2D c = centres[i];
      const double t = len2 > 0.0 ? std::clamp(((c.x_m - a.x_m) * dx + (c.y_m - a.y_m) * dy) / len2, 0.0, 1.0) : 0.0;
      const Point2D s{a.x_m + t * dx, a.y_m + t * dy};
      const double d2 = (c.x_m - s.x_m) * (c.x_m - s.x_m) + (c.y_m - s.y_m) * (c.y_m - s.y_m);
      if (d2 >= best2) continue;
      // S on a cell centre of the leg (legs of lanes run along cell rows or columns)
      const CellIndex sc = grid_.cell_at(s);
      if (!grid_.contains(sc) || !planner_.traversable(sc)) continue;
      // snapped to a cell centre, S may leave the leg: both halves must stay in plain sight
      if (!planner_.line_of_sight(grid_.cell_at(a), sc) || !planner_.line_of_sight(sc, grid_.cell_at(b))) continue;
      best2 = d2, best_leg = k, best_cell = i, split = sc;
    }
  }
  if (path.size() > tour_begin) {
    const Point2D end = path.back();
    for (const Point2D c : centres) {
      // after the end: |end c| against 2 |S c| there and back
      if ((c.x_m - end.x_m) * (c.x_m - end.x_m) + (c.y_m - end.y_m) * (c.y_m - end.y_m) < 4.0 * best2) {
        return append_from(r, cur, piece, start);
      }
    }
  }
  if (!std::isfinite(best2)) return append_from(r, cur, piece, start);
  const CellIndex entry = piece.cells[best_cell];
  std::vector<Point2D> detour;
  detour.push_back(grid_.cell_center(split));
  link(detour, split, entry);
  for (std::size_t j = 1; j <= piece.cells.size(); ++j) {
    detour.push_back(grid_.cell_center(piece.cells[(best_cell + j) % piece.cells.size()]));
  }
  link(detour, entry, split);
  // S itself is on the leg; it is not repeated where it coincides with the leg's ends
  const auto same = [](Point2D p, Point2D q) { return std::hypot(p.x_m - q.x_m, p.y_m - q.y_m) < 1e-9; };
  if (same(detour.back(), path[best_leg + 1])) detour.pop_back();
  if (same(detour.front(), path[best_leg])) detour.erase(detour.begin());
  r.path.insert(r.path.begin() + static_cast<std::ptrdiff_t>(best_leg + 1), detour.begin(), detour.end());
  ++r.passes;
}

void CoveragePlanner::append_from(CoverageResult& r, CellIndex& cur, const RoundPiece& piece, std::optional<Point2D> start) {
  // a closed piece entered at its cell nearest to the robot
  std::size_t entry = 0;
  long long best = std::numeric_limits<long long>::max();
  for (std::size_t k = 0; k < piece.cells.size(); ++k) {
    const long long d = cur.x < 0 ? 0 : dist2(cur, piece.cells[k]);
    if (d < best) best = d, entry = k;
  }
  RoundPiece rotated = piece;
  std::rotate(rotated.cells.begin(), rotated.cells.begin() + static_cast<std::ptrdiff_t>(entry), rotated.cells.end());
  append_piece(r, cur, rotated, start);
}

}  // namespace tripodal::navi
