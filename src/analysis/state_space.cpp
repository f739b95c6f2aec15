// Breadth-first exploration over a packed state store.
//  - A marking is packed into 64-bit words, one bit field per place, no field straddling a word;
//    only the bytes holding fields are stored (little-endian), contiguously in one arena.
//  - Firing a transition is one wrapping add per touched word: the packed word is the sum of
//    count << shift over its fields, and the result of an enabled firing fits every field, so
//    adding sum((produced - consumed) << shift) modulo 2^64 gives the successor exactly.
//  - The hash set holds (32-bit hash tag, state index) pairs with linear probing, so a probe
//    only touches the arena when the tags agree.
//  - A place whose bound is unknown starts narrow; a firing that would overflow its field stops
//    the search, the field is doubled and the search restarts (at most 3 times per place).
//  - Large nets (a dense marking over 64 bytes, few places marked) use the sparse store instead:
//    a state is its marked places as (place << 32 | count) words in place order, and a state
//    costs O(marked places + the transitions watching them), not O(places + transitions). A
//    chain of n places then takes O(n) time and memory instead of O(n^2).
#include "tripodal/analysis/state_space.hpp"

#include <algorithm>
#include <bit>
#include <cstring>
#include <stdexcept>

#include "compiled_net.hpp"

namespace tripodal::analysis {

std::string_view to_string(Semantics s) noexcept {
  switch (s) {
    case Semantics::engine: return "engine";
    case Semantics::interleaving: return "interleaving";
  }
  return "?";
}

std::string_view to_string(StopReason r) noexcept {
  switch (r) {
    case StopReason::complete: return "complete";
    case StopReason::max_states: return "max_states";
    case StopReason::max_memory: return "max_memory";
    case StopReason::token_overflow: return "token_overflow";
  }
  return "?";
}

namespace {

constexpr StateId kNoState = 0xFFFFFFFFU;
constexpr std::size_t kMaxWords = 1U << 20;
constexpr std::size_t kDenseWordsAlways = 8;  // up to 64 bytes a marking is always stored dense

struct WordDelta {
  std::uint32_t word = 0;
  std::uint64_t add = 0;  // wrapping sum of (produced - consumed) << shift
};

inline std::uint64_t mix(std::uint64_t h) noexcept {
  h ^= h >> 30;
  h *= 0xbf58476d1ce4e5b9ULL;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebULL;
  h ^= h >> 31;
  return h;
}

}  // namespace

struct StateSpace::Impl {
  // --- layout -------------------------------------------------------------------------------
  std::size_t places = 0;
  std::vector<std::uint8_t> bits;
  std::vector<std::uint32_t> word_of;
  std::vector<std::uint8_t> shift_of;
  std::vector<std::uint64_t> field_max;
  std::size_t words = 0;
  std::size_t stride = 0;  // bytes stored per state

  // --- store --------------------------------------------------------------------------------
  std::vector<std::uint8_t> arena;
  std::vector<std::uint64_t> table;  // 0 = empty, else (tag << 32) | (index + 1)
  int table_shift = 32;
  std::size_t count = 0;
  std::vector<StateId> parent;
  std::vector<TransitionIndex> via;
  bool keep_edges = false;
  std::vector<std::uint64_t> edge_begin;
  std::vector<StateId> edge_targets;
  std::size_t max_states = 0;
  std::size_t max_memory = 0;
  // The sparse store: state s is entries[entry_begin[s] .. entry_begin[s + 1]).
  bool sparse = false;
  std::vector<std::uint64_t> entries;
  std::vector<std::uint64_t> entry_begin;

  // --- results ------------------------------------------------------------------------------
  std::size_t expanded = 0;
  std::size_t edges = 0;
  StopReason stop = StopReason::complete;
  std::vector<Tokens> max_tokens;
  std::vector<std::uint8_t> fired;
  std::vector<StateId> deadlocks;
  std::vector<StateId> outcome_states;
  std::size_t restarts = 0;

  // --- scratch for the successors of one state ----------------------------------------------
  std::vector<std::uint64_t> batch_words;
  std::vector<TransitionIndex> batch_t;
  std::vector<std::uint64_t> batch_hash;
  std::vector<std::size_t> batch_begin;  // sparse: batch_words[batch_begin[i] .. batch_begin[i + 1])

  void layout(const std::vector<std::uint8_t>& b) {
    bits = b;
    places = b.size();
    word_of.assign(places, 0);
    shift_of.assign(places, 0);
    field_max.assign(places, 0);
    std::size_t word = 0;
    std::size_t used = 0;
    for (std::size_t p = 0; p < places; ++p) {
      if (used + b[p] > 64) {
        ++word;
        used = 0;
      }
      word_of[p] = static_cast<std::uint32_t>(word);
      shift_of[p] = static_cast<std::uint8_t>(used);
      field_max[p] = (std::uint64_t{1} << b[p]) - 1;
      used += b[p];
    }
    words = places == 0 ? 1 : word + 1;
    if (words > kMaxWords) throw std::length_error("net too large for the state store");
    const std::size_t last_bytes = used == 0 ? 1 : (used + 7) / 8;
    stride = std::endian::native == std::endian::little ? (words - 1) * 8 + last_bytes : words * 8;
  }

  [[nodiscard]] std::size_t memory() const noexcept {
    return arena.capacity() + table.capacity() * sizeof(std::uint64_t) + parent.capacity() * sizeof(StateId) +
           via.capacity() * sizeof(TransitionIndex) + edge_begin.capacity() * sizeof(std::uint64_t) +
           edge_targets.capacity() * sizeof(StateId) + entries.capacity() * sizeof(std::uint64_t) +
           entry_begin.capacity() * sizeof(std::uint64_t);
  }

  void pack(const Tokens* m, std::uint64_t* w) const noexcept {
    std::fill(w, w + words, 0);
    for (std::size_t p = 0; p < places; ++p) w[word_of[p]] |= std::uint64_t{m[p]} << shift_of[p];
  }
  void unpack(const std::uint64_t* w, Tokens* m) const noexcept {
    for (std::size_t p = 0; p < places; ++p) m[p] = static_cast<Tokens>((w[word_of[p]] >> shift_of[p]) & field_max[p]);
  }
  void load(StateId s, std::uint64_t* w) const noexcept {
    w[words - 1] = 0;
    std::memcpy(w, arena.data() + std::size_t{s} * stride, stride);
  }
  [[nodiscard]] std::uint64_t hash(const std::uint64_t* w) const noexcept {
    std::uint64_t h = 0x9E3779B97F4A7C15ULL * (words + 1);
    for (std::size_t i = 0; i < words; ++i) h = mix(h ^ w[i]) + i;
    return h;
  }

  // The slot of a hash is the top bits of its 32-bit tag, so growing the table re-slots every
  // entry from the table alone, without touching the arena or hashing again.
  [[nodiscard]] std::size_t slot_of(std::uint64_t tag) const noexcept { return static_cast<std::size_t>(tag >> table_shift); }

  [[nodiscard]] bool equal(StateId s, const std::uint64_t* w) const noexcept {
    const std::uint8_t* a = arena.data() + std::size_t{s} * stride;
    std::size_t i = 0;
    for (; i + 8 <= stride; i += 8) {
      std::uint64_t x = 0;
      std::memcpy(&x, a + i, 8);
      if (x != w[i / 8]) return false;
    }
    if (i == stride) return true;
    const auto* b = reinterpret_cast<const std::uint8_t*>(w);
    for (; i < stride; ++i) {
      if (a[i] != b[i]) return false;
    }
    return true;
  }

  [[nodiscard]] static std::uint64_t hash_sparse(const std::uint64_t* e, std::size_t n) noexcept {
    std::uint64_t h = 0x9E3779B97F4A7C15ULL * (n + 1);
    for (std::size_t i = 0; i < n; ++i) h = mix(h ^ e[i]) + i;
    return h;
  }

  [[nodiscard]] StateId lookup_sparse(const std::uint64_t* e, std::size_t n, std::uint64_t h) const noexcept {
    if (table.empty()) return kNoState;
    const std::size_t mask = table.size() - 1;
    const std::uint64_t tag = h >> 32;
    for (std::size_t i = slot_of(tag);; i = (i + 1) & mask) {
      const std::uint64_t x = table[i];
      if (x == 0) return kNoState;
      if ((x >> 32) == tag) {
        const StateId s = static_cast<StateId>((x & 0xFFFFFFFFULL) - 1);
        const std::uint64_t b = entry_begin[s];
        if (entry_begin[s + 1] - b == n && std::equal(e, e + n, entries.data() + b)) return s;
      }
    }
  }

  [[nodiscard]] StateId lookup(const std::uint64_t* w, std::uint64_t h) const noexcept {
    if (table.empty()) return kNoState;
    const std::size_t mask = table.size() - 1;
    const std::uint64_t tag = h >> 32;
    for (std::size_t i = slot_of(tag);; i = (i + 1) & mask) {
      const std::uint64_t e = table[i];
      if (e == 0) return kNoState;
      if ((e >> 32) == tag) {
        const StateId s = static_cast<StateId>((e & 0xFFFFFFFFULL) - 1);
        if (equal(s, w)) return s;
      }
    }
  }

  void place_entry(std::uint64_t entry) noexcept {
    const std::size_t mask = table.size() - 1;
    std::size_t i = slot_of(entry >> 32);
    while (table[i] != 0) i = (i + 1) & mask;
    table[i] = entry;
  }

  // Grows the table or the per-state arrays if needed; false when the memory cap forbids it.
  bool make_room() {
    if ((count + 1) * 10 > table.size() * 7) {
      const std::size_t size = std::max<std::size_t>(table.size() * 2, 64);
      if (memory() + size * sizeof(std::uint64_t) > max_memory) return false;
      std::vector<std::uint64_t> old(size, 0);
      old.swap(table);
      table_shift = 32 - std::countr_zero(size);
      for (const std::uint64_t e : old) {
        if (e != 0) place_entry(e);
      }
    }
    if (count == parent.capacity()) {
      const std::size_t cap = std::min(std::max<std::size_t>(parent.capacity() * 2, 64), max_states);
      const std::size_t per_state = stride + sizeof(StateId) + sizeof(TransitionIndex) +
                                    (keep_edges ? sizeof(std::uint64_t) : 0) + (sparse ? sizeof(std::uint64_t) : 0);
      if (memory() + cap * per_state > max_memory) return false;
      arena.reserve(cap * stride);
      parent.reserve(cap);
      via.reserve(cap);
      if (keep_edges) edge_begin.reserve(cap + 1);
      if (sparse) entry_begin.reserve(cap + 1);
    }
    return true;
  }

  // The sparse counterpart of insert().
  std::pair<StateId, bool> insert_sparse(const std::uint64_t* e, std::size_t n, std::uint64_t h, StateId from,
                                         TransitionIndex t) {
    const StateId found = lookup_sparse(e, n, h);
    if (found != kNoState) return {found, false};
    if (count >= max_states) {
      stop = StopReason::max_states;
      return {kNoState, false};
    }
    if (!make_room()) {
      stop = StopReason::max_memory;
      return {kNoState, false};
    }
    if (entries.size() + n > entries.capacity()) {
      const std::size_t cap = std::max({entries.capacity() * 2, entries.size() + n, std::size_t{4096}});
      if (memory() + cap * sizeof(std::uint64_t) > max_memory) {
        stop = StopReason::max_memory;
        return {kNoState, false};
      }
      entries.reserve(cap);
    }
    const auto s = static_cast<StateId>(count++);
    entries.insert(entries.end(), e, e + n);
    entry_begin.push_back(entries.size());
    parent.push_back(from);
    via.push_back(t);
    place_entry(((h >> 32) << 32) | (std::uint64_t{s} + 1));
    return {s, true};
  }

  // Returns the state and whether it is new; kNoState with `stop` set when a limit is hit.
  std::pair<StateId, bool> insert(const std::uint64_t* w, std::uint64_t h, StateId from, TransitionIndex t) {
    const StateId found = lookup(w, h);
    if (found != kNoState) return {found, false};
    if (count >= max_states) {
      stop = StopReason::max_states;
      return {kNoState, false};
    }
    if (!make_room()) {
      stop = StopReason::max_memory;
      return {kNoState, false};
    }
    const auto s = static_cast<StateId>(count++);
    const auto* bytes = reinterpret_cast<const std::uint8_t*>(w);
    arena.insert(arena.end(), bytes, bytes + stride);
    parent.push_back(from);
    via.push_back(t);
    place_entry(((h >> 32) << 32) | (std::uint64_t{s} + 1));
    return {s, true};
  }

  void reset() {
    arena = {};
    table = {};
    table_shift = 32;
    parent = {};
    via = {};
    edge_begin = {};
    edge_targets = {};
    entries = {};
    entry_begin = {};
    count = expanded = edges = 0;
    stop = StopReason::complete;
    max_tokens.assign(places, 0);
    deadlocks.clear();
    outcome_states.clear();
  }

  // Returns a place whose field overflowed (the caller widens it and re-runs), or nullopt.
  std::optional<PlaceIndex> run(const detail::CompiledNet& net, const Marking& initial, bool stop_at_outcome) {
    reset();
    fired.assign(net.transitions, 0);
    // Per transition, the packed delta per touched word.
    std::vector<std::uint32_t> delta_begin{0};
    std::vector<WordDelta> deltas;
    for (TransitionIndex t = 0; t < net.transitions; ++t) {
      const std::size_t first = deltas.size();
      for (std::uint32_t i = net.change_begin[t]; i < net.change_begin[t + 1]; ++i) {
        const detail::Change& c = net.changes[i];
        const std::uint32_t w = word_of[c.place];
        auto it = std::find_if(deltas.begin() + static_cast<std::ptrdiff_t>(first), deltas.end(),
                               [&](const WordDelta& d) { return d.word == w; });
        if (it == deltas.end()) {
          deltas.push_back({w, 0});
          it = deltas.end() - 1;
        }
        it->add += (std::uint64_t{c.produced} << shift_of[c.place]) - (std::uint64_t{c.consumed} << shift_of[c.place]);
      }
      delta_begin.push_back(static_cast<std::uint32_t>(deltas.size()));
    }

    std::vector<std::uint64_t> cur(words);
    std::vector<Tokens> m(std::max<std::size_t>(places, 1));
    for (std::size_t p = 0; p < places; ++p) {
      if (initial[p] > field_max[p]) return static_cast<PlaceIndex>(p);
    }
    pack(initial.data(), cur.data());
    if (insert(cur.data(), hash(cur.data()), kNoState, 0).first == kNoState) return std::nullopt;
    if (keep_edges) edge_begin.push_back(0);

    std::optional<PlaceIndex> overflow;
    while (expanded < count) {
      const auto s = static_cast<StateId>(expanded);
      load(s, cur.data());
      unpack(cur.data(), m.data());
      bool outcome = false;
      for (std::size_t p = 0; p < places; ++p) {
        max_tokens[p] = std::max(max_tokens[p], m[p]);
        outcome = outcome || (m[p] != 0 && net.is_outcome[p] != 0);
      }
      if (outcome) outcome_states.push_back(s);
      std::size_t successors = 0;
      bool abort = false;
      batch_t.clear();
      if (!(outcome && stop_at_outcome)) {
        net.successors(m.data(), [&](TransitionIndex t) {
          if (abort) return;
          for (std::uint32_t i = net.change_begin[t]; i < net.change_begin[t + 1]; ++i) {
            const detail::Change& c = net.changes[i];
            if (c.produced > c.consumed &&
                std::uint64_t{m[c.place]} + (c.produced - c.consumed) > field_max[c.place]) {
              abort = true;
              overflow = c.place;
              return;
            }
          }
          const std::size_t k = batch_t.size();
          batch_t.push_back(t);
          if (batch_words.size() < (k + 1) * words) batch_words.resize((k + 1) * words * 2);
          std::uint64_t* next = batch_words.data() + k * words;
          std::copy(cur.begin(), cur.end(), next);
          for (std::uint32_t i = delta_begin[t]; i < delta_begin[t + 1]; ++i) next[deltas[i].word] += deltas[i].add;
        });
      }
      if (!abort) {
        // Successors are looked up in a batch: first every hash-set slot is prefetched, then the
        // arena entry each slot points to, so the cache misses of one state overlap.
        const std::size_t k = batch_t.size();
        batch_hash.resize(k);
        for (std::size_t i = 0; i < k; ++i) {
          batch_hash[i] = hash(batch_words.data() + i * words);
          if (!table.empty()) __builtin_prefetch(&table[slot_of(batch_hash[i] >> 32)]);
        }
        if (!table.empty()) {
          for (std::size_t i = 0; i < k; ++i) {
            const std::uint64_t e = table[slot_of(batch_hash[i] >> 32)];
            if (e != 0) __builtin_prefetch(arena.data() + ((e & 0xFFFFFFFFULL) - 1) * stride);
          }
        }
        for (std::size_t i = 0; i < k && !abort; ++i) {
          const TransitionIndex t = batch_t[i];
          const auto [target, inserted] = insert(batch_words.data() + i * words, batch_hash[i], s, t);
          if (target == kNoState) {
            abort = true;
            break;
          }
          if (!add_edge(target)) {
            abort = true;
            break;
          }
          ++successors;
          fired[t] = 1;
        }
      }
      if (abort) {
        if (keep_edges) edge_targets.resize(edge_begin.back());
        if (overflow) {
          if (bits[*overflow] >= 32) {
            stop = StopReason::token_overflow;
            return std::nullopt;
          }
          return overflow;
        }
        return std::nullopt;  // a limit: `stop` says which
      }
      edges += successors;
      if (successors == 0 && !outcome) deadlocks.push_back(s);
      if (keep_edges) edge_begin.push_back(edge_targets.size());
      ++expanded;
    }
    return std::nullopt;
  }

  // The search over the sparse store. A place holds up to 2^32 - 1 tokens; no field to widen.
  void run_sparse(const detail::CompiledNet& net, const Marking& initial, bool stop_at_outcome) {
    reset();
    fired.assign(net.transitions, 0);
    entry_begin.push_back(0);
    std::vector<std::uint64_t> cur;
    for (std::size_t p = 0; p < places; ++p) {
      if (initial[p] != 0) cur.push_back((std::uint64_t{p} << 32) | initial[p]);
    }
    if (insert_sparse(cur.data(), cur.size(), hash_sparse(cur.data(), cur.size()), kNoState, 0).first == kNoState) {
      return;
    }
    if (keep_edges) edge_begin.push_back(0);

    std::vector<Tokens> m(std::max<std::size_t>(places, 1), 0);  // the expanded marking; zero between states
    std::vector<TransitionIndex> candidates;
    const auto by_rank = [&](TransitionIndex a, TransitionIndex b) { return net.rank[a] < net.rank[b]; };
    while (expanded < count) {
      const auto s = static_cast<StateId>(expanded);
      cur.assign(entries.begin() + static_cast<std::ptrdiff_t>(entry_begin[s]),
                 entries.begin() + static_cast<std::ptrdiff_t>(entry_begin[s + 1]));
      bool outcome = false;
      candidates.clear();
      for (const std::uint64_t e : cur) {
        const auto p = static_cast<std::size_t>(e >> 32);
        const auto k = static_cast<Tokens>(e);
        m[p] = k;
        max_tokens[p] = std::max(max_tokens[p], k);
        outcome = outcome || net.is_outcome[p] != 0;
        candidates.insert(candidates.end(), net.watchers.begin() + net.watch_begin[p],
                          net.watchers.begin() + net.watch_begin[p + 1]);
      }
      if (outcome) outcome_states.push_back(s);
      bool abort = false;
      batch_t.clear();
      batch_begin.assign(1, 0);
      if (!(outcome && stop_at_outcome)) {
        candidates.insert(candidates.end(), net.unwatched.begin(), net.unwatched.end());
        std::sort(candidates.begin(), candidates.end(), by_rank);
        net.successors_among(m.data(), candidates, [&](TransitionIndex t) {
          if (abort) return;
          // The successor: the marked places merged with the places t changes.
          std::size_t out = batch_begin.back();
          const std::size_t need = out + cur.size() + (net.change_begin[t + 1] - net.change_begin[t]);
          if (batch_words.size() < need) batch_words.resize(need * 2);
          std::size_t i = 0;
          for (std::uint32_t c = net.change_begin[t]; c < net.change_begin[t + 1]; ++c) {
            const detail::Change& d = net.changes[c];
            for (; i < cur.size() && (cur[i] >> 32) < d.place; ++i) batch_words[out++] = cur[i];
            if (i < cur.size() && (cur[i] >> 32) == d.place) ++i;
            const std::uint64_t after = std::uint64_t{m[d.place]} - d.consumed + d.produced;
            if (after > 0xFFFFFFFFULL) {
              stop = StopReason::token_overflow;
              abort = true;
              return;
            }
            if (after != 0) batch_words[out++] = (std::uint64_t{d.place} << 32) | after;
          }
          for (; i < cur.size(); ++i) batch_words[out++] = cur[i];
          batch_t.push_back(t);
          batch_begin.push_back(out);
        });
      }
      for (const std::uint64_t e : cur) m[static_cast<std::size_t>(e >> 32)] = 0;
      std::size_t successors = 0;
      if (!abort) {
        const std::size_t k = batch_t.size();
        batch_hash.resize(k);
        for (std::size_t i = 0; i < k; ++i) {
          batch_hash[i] = hash_sparse(batch_words.data() + batch_begin[i], batch_begin[i + 1] - batch_begin[i]);
        }
        for (std::size_t i = 0; i < k && !abort; ++i) {
          const TransitionIndex t = batch_t[i];
          const auto [target, inserted] = insert_sparse(batch_words.data() + batch_begin[i],
                                                        batch_begin[i + 1] - batch_begin[i], batch_hash[i], s, t);
          if (target == kNoState || !add_edge(target)) {
            abort = true;
            break;
          }
          ++successors;
          fired[t] = 1;
        }
      }
      if (abort) {
        if (keep_edges) edge_targets.resize(edge_begin.back());
        return;  // a limit: `stop` says which
      }
      edges += successors;
      if (successors == 0 && !outcome) deadlocks.push_back(s);
      if (keep_edges) edge_begin.push_back(edge_targets.size());
      ++expanded;
    }
  }

  // Records an edge when edges are kept; false when the memory cap forbids it.
  bool add_edge(StateId target) {
    if (!keep_edges) return true;
    if (edge_targets.size() == edge_targets.capacity()) {
      const std::size_t cap = std::max<std::size_t>(edge_targets.capacity() * 2, 4096);
      if (memory() + cap * sizeof(StateId) > max_memory) {
        stop = StopReason::max_memory;
        return false;
      }
      edge_targets.reserve(cap);
    }
    edge_targets.push_back(target);
    return true;
  }
};

StateSpace::StateSpace() : impl_(std::make_unique<Impl>()) {}
StateSpace::~StateSpace() = default;
StateSpace::StateSpace(StateSpace&&) noexcept = default;
StateSpace& StateSpace::operator=(StateSpace&&) noexcept = default;

std::size_t StateSpace::states() const noexcept { return impl_->count; }
std::size_t StateSpace::expanded() const noexcept { return impl_->expanded; }
std::size_t StateSpace::edges() const noexcept { return impl_->edges; }
StopReason StateSpace::stop_reason() const noexcept { return impl_->stop; }
const std::vector<Tokens>& StateSpace::max_tokens() const noexcept { return impl_->max_tokens; }
const std::vector<std::uint8_t>& StateSpace::fired() const noexcept { return impl_->fired; }
const std::vector<StateId>& StateSpace::deadlocks() const noexcept { return impl_->deadlocks; }
const std::vector<StateId>& StateSpace::outcome_states() const noexcept { return impl_->outcome_states; }
std::size_t StateSpace::bytes_per_marking() const noexcept {
  if (!impl_->sparse) return impl_->stride;
  const std::size_t n = std::max<std::size_t>(impl_->count, 1);
  return (impl_->entries.size() * sizeof(std::uint64_t) + n - 1) / n;
}
bool StateSpace::sparse() const noexcept { return impl_->sparse; }
std::size_t StateSpace::memory_bytes() const noexcept { return impl_->memory(); }
const std::vector<std::uint8_t>& StateSpace::bits_per_place() const noexcept { return impl_->bits; }
std::size_t StateSpace::restarts() const noexcept { return impl_->restarts; }
bool StateSpace::has_edges() const noexcept { return impl_->keep_edges; }

double StateSpace::bytes_per_state() const noexcept {
  const std::size_t n = std::max<std::size_t>(impl_->count, 1);
  // What the stored states occupy (not the reserve of the vectors' last doubling).
  const std::size_t used = impl_->count * (impl_->stride + sizeof(StateId) + sizeof(TransitionIndex)) +
                           impl_->table.size() * sizeof(std::uint64_t) +
                           (impl_->entries.size() + impl_->entry_begin.size()) * sizeof(std::uint64_t) +
                           impl_->edge_begin.size() * sizeof(std::uint64_t) +
                           impl_->edge_targets.size() * sizeof(StateId);
  return static_cast<double>(used) / static_cast<double>(n);
}

Marking StateSpace::marking(StateId s) const {
  if (s >= impl_->count) throw std::out_of_range("no state " + std::to_string(s));
  Marking m(impl_->places);
  if (impl_->sparse) {
    for (std::uint64_t i = impl_->entry_begin[s]; i < impl_->entry_begin[s + 1]; ++i) {
      m[static_cast<std::size_t>(impl_->entries[i] >> 32)] = static_cast<Tokens>(impl_->entries[i]);
    }
    return m;
  }
  std::vector<std::uint64_t> w(impl_->words);
  impl_->load(s, w.data());
  impl_->unpack(w.data(), m.data());
  return m;
}

std::vector<TransitionIndex> StateSpace::path_to(StateId s) const {
  if (s >= impl_->count) throw std::out_of_range("no state " + std::to_string(s));
  std::vector<TransitionIndex> path;
  for (StateId at = s; impl_->parent[at] != kNoState; at = impl_->parent[at]) path.push_back(impl_->via[at]);
  std::reverse(path.begin(), path.end());
  return path;
}

std::span<const StateId> StateSpace::successors(StateId s) const {
  if (!impl_->keep_edges) throw std::logic_error("successors: the exploration did not keep edges");
  if (s >= impl_->expanded) return {};
  return {impl_->edge_targets.data() + impl_->edge_begin[s], impl_->edge_begin[s + 1] - impl_->edge_begin[s]};
}

std::optional<StateId> StateSpace::find(const Marking& m) const {
  if (m.size() != impl_->places) return std::nullopt;
  if (impl_->sparse) {
    std::vector<std::uint64_t> e;
    for (std::size_t p = 0; p < m.size(); ++p) {
      if (m[p] != 0) e.push_back((std::uint64_t{p} << 32) | m[p]);
    }
    const StateId s = impl_->lookup_sparse(e.data(), e.size(), Impl::hash_sparse(e.data(), e.size()));
    if (s == kNoState) return std::nullopt;
    return s;
  }
  for (std::size_t p = 0; p < m.size(); ++p) {
    if (m[p] > impl_->field_max[p]) return std::nullopt;
  }
  std::vector<std::uint64_t> w(impl_->words);
  impl_->pack(m.data(), w.data());
  const StateId s = impl_->lookup(w.data(), impl_->hash(w.data()));
  if (s == kNoState) return std::nullopt;
  return s;
}

StateSpace explore(const PetriNet& net, const ExploreOptions& options) {
  const detail::CompiledNet compiled(net, options.parameters, {.semantics = options.semantics});
  const Marking initial = net.initial_marking();
  std::vector<std::uint8_t> bits(initial.size());
  for (std::size_t p = 0; p < initial.size(); ++p) {
    std::optional<Tokens> bound;
    if (p < options.place_bounds.size()) bound = options.place_bounds[p];
    if (const auto& cap = net.places()[p].capacity; cap && (!bound || *cap < *bound)) bound = *cap;
    const Tokens b = bound ? std::max(*bound, initial[p]) : std::max<Tokens>(initial[p], 15);
    bits[p] = static_cast<std::uint8_t>(std::max(1, static_cast<int>(std::bit_width(b))));
  }
  StateSpace result;
  StateSpace::Impl& impl = *result.impl_;
  impl.keep_edges = options.keep_edges;
  impl.max_states = std::max<std::size_t>(options.max_states, 1);
  impl.max_memory = options.max_memory_bytes;
  impl.layout(bits);
  std::size_t marked = 0;
  for (const Tokens k : initial) marked += k != 0 ? 1 : 0;
  impl.sparse = options.store == MarkingStore::sparse ||
                (options.store == MarkingStore::automatic && impl.words > kDenseWordsAlways &&
                 16 * (marked + 1) < impl.stride);
  if (impl.sparse) {
    impl.bits.assign(initial.size(), 32);
    impl.stride = 0;
    impl.run_sparse(compiled, initial, options.stop_at_outcome);
    return result;
  }
  for (;;) {
    impl.layout(bits);
    const auto overflow = impl.run(compiled, initial, options.stop_at_outcome);
    if (!overflow) break;
    bits[*overflow] = static_cast<std::uint8_t>(std::min(32, bits[*overflow] * 2));
    ++impl.restarts;
  }
  return result;
}

}  // namespace tripodal::analysis
