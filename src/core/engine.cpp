// The engine compiles a net into flat arrays once:
//  - per transition, one Check per place it depends on (lo <= marking <= hi folds input, read,
//    inhibitor and capacity conditions together), one PlaceChange per place it touches (what
//    observers see) and one Effect per place whose marking it changes (what a firing executes);
//  - per place, the transitions whose Checks read it (CSR), per fact the transitions whose guards
//    read it;
//  - a rank per transition: the conflict order (priority descending, then declaration order).
// Enabled immediate transitions and due delayed ones sit in a hierarchical bitset over ranks, so
// the next transition to fire is found in O(log64 n); enabled delayed transitions wait in an
// indexed min-heap of deadlines. A firing re-examines only the transitions next to the places it
// changed, so its cost does not depend on the size of the net, and nothing allocates.
#include "tripodal/core/engine.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <bit>
#include <cassert>
#include <limits>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "net_compile.hpp"
#include "tripodal/core/diagnostic.hpp"

namespace tripodal {

namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
constexpr std::size_t kTailWindow = 1024;  // firings kept to name the transitions of a livelock

enum class Kind : std::uint8_t { immediate, delayed, event };

/// What a firing reads of a transition, in one record: a firing touches the records of the
/// transition and of its neighbours only. No member is a char type, so that stores to the
/// marking and flags do not force the compiler to reload every array pointer.
struct TransitionCode {
  std::uint32_t check_begin = 0;   // [check_begin, check_end) in checks
  std::uint32_t check_end = 0;
  std::uint32_t effect_begin = 0;  // [effect_begin, effect_end) in effects
  std::uint32_t effect_end = 0;
  std::uint32_t rank = 0;          // conflict order: priority descending, then declaration order
  Kind kind = Kind::immediate;
  bool enabled = false;
  bool marks_bound = false;        // an effect changes a place that binds a behavior or process
  const Guard* guard = nullptr;
};

/// Per place: whether it binds a behavior or process (reported in StepResult::activated /
/// deactivated), and whether this step changed its marking. Not a char type, for the same reason.
enum class PlaceFlags : std::uint8_t { none = 0, bound = 1, touched = 2, bound_touched = 3 };

/// What a firing does to one place whose marking it changes, with everything the firing then
/// needs in one record: the place's watchers are found without a look-up in watch_begin.
struct Effect {
  PlaceIndex place = 0;
  Tokens delta = 0;  // produced - consumed, modulo 2^32: the firing adds it
  std::uint32_t watch_begin = 0;  // [watch_begin, watch_end) in watchers
  std::uint32_t watch_end = 0;
};

using Check = detail::PlaceBound;

/// A transition's Check on one place, listed under that place: when a firing changes the place,
/// the bound alone decides whether an enabled watcher stays enabled.
struct Watch {
  TransitionIndex transition = 0;
  Tokens lo = 0;
  Tokens hi = std::numeric_limits<Tokens>::max();
  // This bound is the transition's whole enabling condition (one Check, no guard): when it holds
  // the transition is enabled without a call to check(). Most transitions of a sequencing net
  // (one input place, no guard) are of this shape.
  bool alone = false;
};

/// A set of small integers with O(log64 n) insert, erase and find-first: one bit per element at
/// the bottom level, one bit per non-empty word at each level above, a single word at the top.
/// The levels share one array so that a step touches as few cache lines as possible.
class RankSet {
 public:
  void init(std::size_t n) {
    levels_ = 0;
    std::size_t bits = std::max<std::size_t>(n, 1);
    std::size_t total = 0;
    for (;;) {
      const std::size_t words = (bits + 63) / 64;
      if (levels_ == kMaxLevels) throw std::length_error("RankSet: too many elements");
      begin_[levels_] = static_cast<std::uint32_t>(total);
      size_[levels_] = static_cast<std::uint32_t>(words);
      ++levels_;
      total += words;
      if (words == 1) break;
      bits = words;
    }
    top_ = begin_[levels_ - 1];
    words_.assign(total, 0);
  }
  void clear() noexcept { std::fill(words_.begin(), words_.end(), 0); }
  [[nodiscard]] bool empty() const noexcept { return words_[top_] == 0; }
  [[nodiscard]] bool test(std::uint32_t i) const noexcept { return ((words_[i >> 6] >> (i & 63)) & 1U) != 0; }
  // Level 0 is handled inline: in most calls its word was already non-empty (insert) or stays
  // non-empty (erase), and the levels above are not touched.
  void insert(std::uint32_t i) noexcept {
    std::uint64_t& word = words_[i >> 6];
    const bool was_empty = word == 0;
    word |= std::uint64_t{1} << (i & 63);
    if (was_empty && levels_ > 1) insert_above(i >> 6);
  }
  void erase(std::uint32_t i) noexcept {
    std::uint64_t& word = words_[i >> 6];
    word &= ~(std::uint64_t{1} << (i & 63));
    if (word == 0 && levels_ > 1) erase_above(i >> 6);
  }
  /// Smallest element; the set must not be empty.
  [[nodiscard]] std::uint32_t first() const noexcept {
    const std::uint64_t* words = words_.data();
    auto index = static_cast<std::uint32_t>(std::countr_zero(words[top_]));
    for (std::uint32_t l = levels_ - 1; l-- > 0;) {
      index = index * 64 + static_cast<std::uint32_t>(std::countr_zero(words[begin_[l] + index]));
    }
    return index;
  }
  /// Smallest element >= i; kNone when there is none.
  [[nodiscard]] std::uint32_t next(std::uint32_t i) const noexcept { return next_at(0, i); }

 private:
  static constexpr std::uint32_t kMaxLevels = 6;  // 64^6 elements

  void insert_above(std::uint32_t i) noexcept {
    for (std::uint32_t l = 1; l < levels_; ++l) {
      std::uint64_t& word = words_[begin_[l] + (i >> 6)];
      const bool was_empty = word == 0;
      word |= std::uint64_t{1} << (i & 63);
      if (!was_empty) return;
      i >>= 6;
    }
  }
  void erase_above(std::uint32_t i) noexcept {
    for (std::uint32_t l = 1; l < levels_; ++l) {
      std::uint64_t& word = words_[begin_[l] + (i >> 6)];
      word &= ~(std::uint64_t{1} << (i & 63));
      if (word != 0) return;
      i >>= 6;
    }
  }

  // Smallest set bit >= i at `level`: within i's word, else in the next non-empty word, which
  // the level above finds.
  [[nodiscard]] std::uint32_t next_at(std::uint32_t level, std::uint32_t i) const noexcept {
    const std::uint32_t w = i >> 6;
    if (w >= size_[level]) return kNone;
    const std::uint64_t* words = words_.data() + begin_[level];
    const std::uint64_t bits = words[w] & (~std::uint64_t{0} << (i & 63));
    if (bits != 0) return w * 64 + static_cast<std::uint32_t>(std::countr_zero(bits));
    if (level + 1 == levels_) return kNone;
    const std::uint32_t next_word = next_at(level + 1, w + 1);
    if (next_word == kNone) return kNone;
    return next_word * 64 + static_cast<std::uint32_t>(std::countr_zero(words[next_word]));
  }

  std::vector<std::uint64_t> words_;  // level 0 (one bit per element) first
  std::uint32_t begin_[kMaxLevels] = {};
  std::uint32_t size_[kMaxLevels] = {};
  std::uint32_t levels_ = 0;
  std::uint32_t top_ = 0;  // the single word of the top level
};

/// Min-heap of (deadline, rank) with a position index per transition, so a transition that stops
/// being enabled leaves the heap in O(log n). Capacity is reserved up front: push never allocates.
class TimerHeap {
 public:
  struct Entry {
    Time deadline{};
    std::uint32_t rank = 0;
    TransitionIndex transition = 0;
  };

  void init(std::size_t transitions) {
    heap_.clear();
    heap_.reserve(transitions);
    pos_.assign(transitions, kNone);
  }
  void clear() noexcept {
    for (const Entry& e : heap_) pos_[e.transition] = kNone;
    heap_.clear();
  }
  [[nodiscard]] bool empty() const noexcept { return heap_.empty(); }
  [[nodiscard]] const Entry& top() const noexcept { return heap_.front(); }
  [[nodiscard]] bool contains(TransitionIndex t) const noexcept { return pos_[t] != kNone; }
  /// The top is the only entry at its deadline (its children, the next candidates, are later).
  [[nodiscard]] bool top_alone() const noexcept {
    const std::size_t n = heap_.size();
    const Time d = heap_.front().deadline;
    return (n < 2 || heap_[1].deadline > d) && (n < 3 || heap_[2].deadline > d);
  }

  void push(TransitionIndex t, Time deadline, std::uint32_t rank) noexcept {
    assert(heap_.size() < heap_.capacity());
    heap_.push_back(Entry{deadline, rank, t});
    pos_[t] = static_cast<std::uint32_t>(heap_.size() - 1);
    sift_up(heap_.size() - 1);
  }
  TransitionIndex pop() noexcept {
    const TransitionIndex t = heap_.front().transition;
    remove_at(0);
    return t;
  }
  void remove(TransitionIndex t) noexcept { remove_at(pos_[t]); }

 private:
  static bool before(const Entry& a, const Entry& b) noexcept {
    return a.deadline != b.deadline ? a.deadline < b.deadline : a.rank < b.rank;
  }
  void place(std::size_t i, const Entry& e) noexcept {
    heap_[i] = e;
    pos_[e.transition] = static_cast<std::uint32_t>(i);
  }
  void sift_up(std::size_t i) noexcept {
    const Entry e = heap_[i];
    while (i > 0) {
      const std::size_t parent = (i - 1) / 2;
      if (!before(e, heap_[parent])) break;
      place(i, heap_[parent]);
      i = parent;
    }
    place(i, e);
  }
  void sift_down(std::size_t i) noexcept {
    const Entry e = heap_[i];
    const std::size_t n = heap_.size();
    for (;;) {
      std::size_t child = 2 * i + 1;
      if (child >= n) break;
      if (child + 1 < n && before(heap_[child + 1], heap_[child])) ++child;
      if (!before(heap_[child], e)) break;
      place(i, heap_[child]);
      i = child;
    }
    place(i, e);
  }
  void remove_at(std::size_t i) noexcept {
    pos_[heap_[i].transition] = kNone;
    const Entry last = heap_.back();
    heap_.pop_back();
    if (i == heap_.size()) return;
    place(i, last);
    sift_up(i);
    sift_down(pos_[last.transition]);
  }

  std::vector<Entry> heap_;
  std::vector<std::uint32_t> pos_;
};

std::shared_ptr<spdlog::logger> engine_logger() {
  static constexpr const char* kName = "tripodal.engine";
  if (auto existing = spdlog::get(kName)) return existing;
  const auto& sinks = spdlog::default_logger()->sinks();
  auto logger = std::make_shared<spdlog::logger>(kName, sinks.begin(), sinks.end());
  try {
    spdlog::initialize_logger(logger);  // registers it and applies the global level
  } catch (const spdlog::spdlog_ex&) {
    // another engine registered it first (constructed on another thread)
    if (auto existing = spdlog::get(kName)) return existing;
  }
  return logger;
}

std::string seconds_text(Time t) { return format_seconds(t, 6) + " s"; }

struct StringHash {
  using is_transparent = void;
  std::size_t operator()(std::string_view s) const noexcept { return std::hash<std::string_view>{}(s); }
};

}  // namespace

std::string_view to_string(StepStatus s) noexcept {
  switch (s) {
    case StepStatus::ok: return "ok";
    case StepStatus::livelock: return "livelock";
    case StepStatus::time_regressed: return "time_regressed";
  }
  return "?";
}

struct Engine::Impl {
  PetriNet net;
  EngineOptions options;
  std::shared_ptr<spdlog::logger> log;

  // --- compiled net ---------------------------------------------------------------------------
  std::vector<TransitionCode> code;          // per transition
  std::vector<TransitionIndex> order;        // rank -> transition
  std::vector<Duration> delay;
  std::vector<EventId> event_of;             // kNone: no event
  std::vector<Check> checks;
  std::vector<PlaceChange> changes;
  std::vector<std::uint32_t> change_begin;  // per transition, CSR into changes (for observers)
  std::vector<Effect> effects;
  std::vector<std::uint32_t> slot_begin;     // into slots
  std::vector<const Value*> slots;
  std::vector<std::uint32_t> watch_begin;    // per place, CSR into watchers
  std::vector<Watch> watchers;
  std::vector<PlaceFlags> place_flags;
  std::vector<PlaceIndex> outcome_places;

  std::vector<Value> parameter_values;       // per declared parameter
  std::vector<Value> fact_values;            // per declared fact
  std::vector<std::uint8_t> fact_known;
  std::vector<std::uint32_t> fact_slot_begin;  // CSR: positions in `slots` reading the fact
  std::vector<std::uint32_t> fact_slots;
  std::vector<std::uint32_t> fact_watch_begin;  // CSR: transitions whose guard reads the fact
  std::vector<TransitionIndex> fact_watchers;

  std::vector<std::string> event_names;
  std::unordered_map<std::string, EventId, StringHash, std::equal_to<>> event_ids;
  std::vector<std::uint32_t> listener_begin;  // per event, CSR, in rank order
  std::vector<TransitionIndex> listeners;
  std::vector<std::uint32_t> listener_pos;    // per event transition: its position in its event's list

  // --- state ----------------------------------------------------------------------------------
  Marking marking;
  std::vector<Time> since;
  RankSet ready;  // ranks of enabled immediate and due delayed transitions
  std::vector<RankSet> event_enabled;  // per event: positions of its enabled listeners
  TimerHeap timers;
  Time now{};
  std::size_t instant_firings = 0;
  std::vector<TransitionIndex> tail;  // ring of the last firings at this instant (power-of-2 size)
  std::size_t tail_mask = 0;
  std::vector<std::uint8_t> reported_active;
  std::vector<PlaceIndex> touched_list;
  std::vector<EngineObserver*> observers;
  StepResult result;
  bool debug_log = false;  // the logger's level, read once per step
  bool reporting = false;  // debug_log or observers: a firing calls report_firing
  bool result_filled = false;  // a list or the error of `result` may be non-empty

  Impl(const PetriNet& n, const ParameterValues& parameters, EngineOptions opts);
  void compile_structure();
  void bind_variables(const ParameterValues& parameters, Diagnostics& problems);

  [[nodiscard]] bool check(TransitionIndex t) const noexcept {
    const TransitionCode& tc = code[t];
    const Check* c = checks.data() + tc.check_begin;
    const Check* const end = checks.data() + tc.check_end;
    const Tokens* const m = marking.data();
    for (; c != end; ++c) {
      const Tokens tokens = m[c->place];
      if (tokens < c->lo || tokens > c->hi) return false;
    }
    if (tc.guard == nullptr) return true;
    return tc.guard->evaluate(
        std::span<const Value* const>(slots.data() + slot_begin[t], slot_begin[t + 1] - slot_begin[t]));
  }

  // Immediate and delayed transitions, the common cases, are handled inline; event transitions
  // out of line.
  void disable(TransitionIndex t) noexcept {
    TransitionCode& tc = code[t];
    if (!tc.enabled) return;
    tc.enabled = false;
    if (tc.kind == Kind::immediate) {
      ready.erase(tc.rank);
    } else if (tc.kind == Kind::delayed) {
      if (timers.contains(t)) {
        timers.remove(t);
      } else {
        ready.erase(tc.rank);  // due: it waits in the ready set
      }
    } else {
      disable_event(t);
    }
  }

  void enable(TransitionIndex t) noexcept {
    TransitionCode& tc = code[t];
    tc.enabled = true;
    if (tc.kind == Kind::immediate) {
      ready.insert(tc.rank);
    } else if (tc.kind == Kind::delayed) {
      timers.push(t, now + delay[t], tc.rank);
    } else {
      enable_event(t);
    }
  }

  [[gnu::noinline]] void disable_event(TransitionIndex t) noexcept { event_enabled[event_of[t]].erase(listener_pos[t]); }

  [[gnu::noinline]] void enable_event(TransitionIndex t) noexcept {
    since[t] = now;  // an event transition with a delay passes events on until it has waited
    event_enabled[event_of[t]].insert(listener_pos[t]);
  }

  void update(TransitionIndex t) noexcept {
    const bool en = check(t);
    if (en == code[t].enabled) return;
    if (en) {
      enable(t);
    } else {
      disable(t);
    }
  }

  // A transition that fired and is still enabled: immediate and event transitions stay where
  // they are; a delayed one (it fired from the ready set) waits for its delay again.
  void restart(TransitionIndex t) noexcept {
    const TransitionCode& tc = code[t];
    if (tc.kind == Kind::delayed) {
      ready.erase(tc.rank);
      timers.push(t, now + delay[t], tc.rank);
    } else if (tc.kind == Kind::event) {
      since[t] = now;
    }
  }

  // Returns false when the livelock budget is exhausted (nothing fired then).
  [[gnu::always_inline]] bool fire(TransitionIndex t, std::string_view event) {
    if (instant_firings == options.max_firings_per_instant) [[unlikely]] {
      report_livelock();
      return false;
    }
    tail[instant_firings & tail_mask] = t;
    ++instant_firings;
    ++result.firings;
    const TransitionCode& tc = code[t];
    if (tc.marks_bound) [[unlikely]] touch_bound(tc);
    // Enabling is a conjunction of one bound per place (and the guard, which a firing does not
    // change). An enabled watcher of a changed place therefore stays enabled exactly while that
    // place's bound holds; a disabled one can only become enabled if that bound now holds, and
    // then the whole check decides. A check may read a place this firing changes later; that
    // place's own watchers are visited then, so every flag is exact after the last effect.
    Tokens* const m = marking.data();
    const Watch* const all_watchers = watchers.data();
    const Effect* const last = effects.data() + tc.effect_end;
    for (const Effect* e = effects.data() + tc.effect_begin; e != last; ++e) {
      const Tokens tokens = m[e->place] += e->delta;
      const Watch* const we = all_watchers + e->watch_end;
      for (const Watch* w = all_watchers + e->watch_begin; w != we; ++w) {
        const bool holds = tokens >= w->lo && tokens <= w->hi;
        if (code[w->transition].enabled) {
          if (!holds) disable(w->transition);
        } else if (holds && (w->alone || check(w->transition))) {
          enable(w->transition);
        }
      }
    }
    // The fired transition starts a new enabling (its delay counts again) if it stays enabled.
    if (code[t].enabled) restart(t);

    if (reporting) [[unlikely]] report_firing(t, event);
    return true;
  }

  // Records the bound places a firing changes, for StepResult::activated / deactivated.
  [[gnu::noinline]] void touch_bound(const TransitionCode& tc) {
    for (std::uint32_t i = tc.effect_begin; i != tc.effect_end; ++i) {
      const PlaceIndex p = effects[i].place;
      if (place_flags[p] != PlaceFlags::bound) continue;
      place_flags[p] = PlaceFlags::bound_touched;
      touched_list.push_back(p);
    }
  }

  [[gnu::noinline]] void report_firing(TransitionIndex t, std::string_view event) {
    if (debug_log) {
      log->debug("{}: fire {} at {:.6f} s{}{}", net.id, net.transition(t).id, to_seconds(now),
                 event.empty() ? "" : " on event ", event);
    }
    const Firing f{now, t, net.transitions()[t].id, event,
                   std::span<const PlaceChange>(changes.data() + change_begin[t], change_begin[t + 1] - change_begin[t]),
                   marking};
    for (EngineObserver* o : observers) o->notify(f);
  }

  bool settle() {
    while (!ready.empty()) {
      if (!fire(order[ready.first()], {})) return false;
    }
    return true;
  }

  bool advance(Time to) {
    while (!timers.empty() && timers.top().deadline <= to) {
      const Time due = timers.top().deadline;
      if (due > now) {
        now = due;
        instant_firings = 0;
      }
      while (!timers.empty() && timers.top().deadline <= now) ready.insert(code[timers.pop()].rank);
      if (!settle()) return false;
    }
    if (to > now) {
      now = to;
      instant_firings = 0;
    }
    return settle();
  }

  bool post(EventId e, std::string_view name) {
    // Enabled listeners in rank order; one waiting out its delay passes the event on.
    const RankSet& candidates = event_enabled[e];
    for (std::uint32_t i = candidates.next(0); i != kNone; i = candidates.next(i + 1)) {
      const TransitionIndex t = listeners[listener_begin[e] + i];
      if (since[t] + delay[t] <= now) {
        if (!fire(t, name)) return false;
        return settle();
      }
    }
    drop(name);
    return true;
  }

  void drop(std::string_view name) {
    result_filled = true;
    result.unconsumed_events.emplace_back(name);
    if (log->should_log(spdlog::level::debug)) {
      log->debug("{}: event {} at {:.6f} s dropped: no enabled transition waits for it", net.id, name,
                 to_seconds(now));
    }
  }

  void report_livelock();
  void begin_step() {
    result.status = StepStatus::ok;
    result.firings = 0;
    // Most steps leave the result's lists empty: clearing five of them each step was a tenth of
    // an idle step. Whatever fills one (a dropped event, a bound place, a livelock, an error)
    // marks the result for the next step's clearing.
    if (result_filled) [[unlikely]]
      clear_result();
    instant_firings = 0;
    debug_log = log->should_log(spdlog::level::debug);
    reporting = debug_log || !observers.empty();  // observers cannot change during a step
  }
  [[gnu::noinline]] void clear_result() noexcept {
    result.unconsumed_events.clear();
    result.activated.clear();
    result.deactivated.clear();
    result.loop.clear();
    result.error.clear();
    result_filled = false;
  }
  // Nothing due and nothing ready: the step only moves the time (most periods of a supervisor),
  // without the call into advance() and its register saves.
  [[nodiscard]] bool idle_until(Time to) const noexcept {
    return ready.empty() && (timers.empty() || timers.top().deadline > to);
  }
  // One delayed transition falls due and nothing else is ready or due at its deadline: what most
  // supervisor steps that fire do. It fires at once, as advance() would fire it (first in the ready
  // set, which would hold it alone), without passing through the ready set.
  // Called when the step is not idle: then an empty ready set means a timer is due.
  [[nodiscard]] bool lone_timer_due() const noexcept { return ready.empty() && timers.top_alone(); }
  bool fire_lone_timer() {
    const Time due = timers.top().deadline;
    if (due > now) {
      now = due;
      instant_firings = 0;
    }
    // Not in the ready set: if the firing disables it, or it restarts, the ready set's erase of its
    // rank clears a bit that is already clear.
    if (!fire(timers.pop(), {})) return false;
    return settle();
  }
  // A step that is not idle. One timer due alone (a supervisor's common firing step) fires
  // without advance()'s loops; what it enables settles, and anything else goes through advance().
  // Out of line, so that the idle step does not save the registers this needs.
  [[gnu::noinline]] void fire_until(Time to) {
    if (lone_timer_due()) {
      if (!fire_lone_timer()) return;
      if (idle_until(to)) {
        if (to > now) {
          now = to;
          instant_firings = 0;
        }
        return;
      }
    }
    advance(to);
  }
  void finish_step() {
    if (!touched_list.empty()) [[unlikely]]
      report_bound_changes();  // most steps change no bound place
  }
  [[gnu::noinline]] void report_bound_changes() {
    result_filled = true;
    for (const PlaceIndex p : touched_list) {
      place_flags[p] = PlaceFlags::bound;
      const std::uint8_t active = marking[p] > 0 ? 1 : 0;
      if (active == reported_active[p]) continue;
      reported_active[p] = active;
      (active != 0 ? result.activated : result.deactivated).push_back(p);
    }
    touched_list.clear();
    if (result.activated.size() > 1) std::sort(result.activated.begin(), result.activated.end());
    if (result.deactivated.size() > 1) std::sort(result.deactivated.begin(), result.deactivated.end());
  }
  bool start_step(Time to) {
    begin_step();
    if (to < now) [[unlikely]] {
      report_time_regressed(to);
      return false;
    }
    return true;
  }
  [[gnu::noinline]] void report_time_regressed(Time to) {
    result_filled = true;
    result.status = StepStatus::time_regressed;
    result.error = "step to " + seconds_text(to) + " is earlier than the engine's time " + seconds_text(now);
  }

  void reset(Time start);
  void set_fact(FactId f, Value value);
};

Engine::Impl::Impl(const PetriNet& n, const ParameterValues& parameters, EngineOptions opts)
    : net(n), options(opts), log(engine_logger()) {
  if (options.max_firings_per_instant == 0) {
    throw std::invalid_argument("EngineOptions::max_firings_per_instant must be at least 1");
  }
  Diagnostics problems;
  compile_structure();
  bind_variables(parameters, problems);
  if (problems.has_errors()) throw ConfigError(std::move(problems));
  reset(options.start_time);
}

void Engine::Impl::compile_structure() {
  const auto& places = net.places();
  const auto& transitions = net.transitions();
  const std::size_t np = places.size();
  const std::size_t nt = transitions.size();

  code.assign(nt, TransitionCode{});
  change_begin.assign(1, 0);
  delay.resize(nt);
  event_of.assign(nt, kNone);

  std::vector<std::vector<Watch>> place_watchers(np);
  std::vector<std::vector<TransitionIndex>> event_listeners;
  for (TransitionIndex t = 0; t < nt; ++t) {
    const Transition& tr = transitions[t];
    delay[t] = tr.delay;
    if (!tr.event.empty()) {
      code[t].kind = Kind::event;
      auto [it, inserted] = event_ids.try_emplace(tr.event, static_cast<EventId>(event_names.size()));
      if (inserted) {
        event_names.push_back(tr.event);
        event_listeners.emplace_back();
      }
      event_of[t] = it->second;
      event_listeners[it->second].push_back(t);
    } else {
      code[t].kind = tr.delay.count() > 0 ? Kind::delayed : Kind::immediate;
    }
    if (tr.guard) code[t].guard = &*tr.guard;

    code[t].check_begin = static_cast<std::uint32_t>(checks.size());
    const std::size_t first_change = changes.size();
    detail::fold_transition(net, tr, {}, checks, changes);
    const bool alone = checks.size() - code[t].check_begin == 1 && code[t].guard == nullptr;
    for (std::size_t i = code[t].check_begin; i < checks.size(); ++i) {
      place_watchers[checks[i].place].push_back(Watch{t, checks[i].lo, checks[i].hi, alone});
    }
    code[t].effect_begin = static_cast<std::uint32_t>(effects.size());
    for (std::size_t i = first_change; i < changes.size(); ++i) {
      const PlaceChange& d = changes[i];
      if (d.produced != d.consumed) effects.push_back(Effect{d.place, d.produced - d.consumed, 0, 0});
    }
    code[t].check_end = static_cast<std::uint32_t>(checks.size());
    change_begin.push_back(static_cast<std::uint32_t>(changes.size()));
    code[t].effect_end = static_cast<std::uint32_t>(effects.size());
  }

  order = detail::conflict_order(net);
  for (std::uint32_t r = 0; r < nt; ++r) code[order[r]].rank = r;

  watch_begin.assign(1, 0);
  for (const auto& w : place_watchers) {
    watchers.insert(watchers.end(), w.begin(), w.end());
    watch_begin.push_back(static_cast<std::uint32_t>(watchers.size()));
  }
  for (Effect& e : effects) {
    e.watch_begin = watch_begin[e.place];
    e.watch_end = watch_begin[e.place + 1];
  }
  listener_begin.assign(1, 0);
  listener_pos.assign(nt, kNone);
  event_enabled.resize(event_listeners.size());
  for (std::size_t e = 0; e < event_listeners.size(); ++e) {
    auto& l = event_listeners[e];
    std::stable_sort(l.begin(), l.end(), [&](TransitionIndex a, TransitionIndex b) { return code[a].rank < code[b].rank; });
    for (std::uint32_t i = 0; i < l.size(); ++i) listener_pos[l[i]] = i;
    listeners.insert(listeners.end(), l.begin(), l.end());
    listener_begin.push_back(static_cast<std::uint32_t>(listeners.size()));
    event_enabled[e].init(l.size());
  }

  place_flags.assign(np, PlaceFlags::none);
  for (PlaceIndex p = 0; p < np; ++p) {
    if (places[p].behavior || places[p].process) place_flags[p] = PlaceFlags::bound;
    if (places[p].outcome != Outcome::none) outcome_places.push_back(p);
  }
  for (TransitionCode& tc : code) {
    for (std::uint32_t i = tc.effect_begin; i != tc.effect_end; ++i) {
      if (place_flags[effects[i].place] != PlaceFlags::none) tc.marks_bound = true;
    }
  }

  marking.assign(np, 0);
  since.assign(nt, Time{});
  ready.init(nt);
  timers.init(nt);
  // A power-of-two ring indexes with a mask: a division per firing costs as much as the rest.
  tail.assign(std::bit_ceil(std::min(kTailWindow, options.max_firings_per_instant)), 0);
  tail_mask = tail.size() - 1;
  reported_active.assign(np, 0);
  touched_list.reserve(np);
  result.unconsumed_events.reserve(16);
  result.activated.reserve(np);
  result.deactivated.reserve(np);
}

void Engine::Impl::bind_variables(const ParameterValues& parameters, Diagnostics& problems) {
  const SourceLocation& where = net.where;
  const std::string net_name = net.id.empty() ? std::string("the net") : "net '" + net.id + "'";

  parameter_values.resize(net.parameters.size());
  for (std::size_t i = 0; i < net.parameters.size(); ++i) {
    const VariableDecl& decl = net.parameters[i];
    const auto given = parameters.find(decl.name);
    if (given != parameters.end()) {
      if (type_of(given->second) != decl.type) {
        problems.error(where, "parameter '" + decl.name + "' of " + net_name + " must be a " +
                                  std::string(to_string(decl.type)) + ", got the " +
                                  std::string(to_string(type_of(given->second))) + " " + to_string(given->second));
      }
      parameter_values[i] = given->second;
    } else if (decl.default_value) {
      if (type_of(*decl.default_value) != decl.type) {
        problems.error(decl.where, "default of parameter '" + decl.name + "' is not a " +
                                       std::string(to_string(decl.type)));
      }
      parameter_values[i] = *decl.default_value;
    } else {
      problems.error(where, "missing required parameter '" + decl.name + "' (" + std::string(to_string(decl.type)) +
                                ") of " + net_name);
    }
  }
  for (const auto& [name, value] : parameters) {
    if (net.find_parameter(name) == nullptr) {
      std::string declared;
      for (const auto& d : net.parameters) declared += (declared.empty() ? "" : ", ") + d.name;
      problems.error(where, "unknown parameter '" + name + "' for " + net_name + " (declared: " +
                                (declared.empty() ? std::string("none") : declared) + ")");
    }
  }

  const std::size_t nf = net.facts.size();
  fact_values.resize(nf);
  fact_known.assign(nf, 0);
  std::vector<std::vector<std::uint32_t>> slots_of_fact(nf);
  std::vector<std::vector<TransitionIndex>> watchers_of_fact(nf);
  slot_begin.assign(1, 0);
  for (TransitionIndex t = 0; t < net.transitions().size(); ++t) {
    const Transition& tr = net.transition(t);
    if (tr.guard) {
      const auto& ids = tr.guard->identifiers();
      for (std::size_t s = 0; s < ids.size(); ++s) {
        const std::string& name = ids[s];
        const VariableDecl* decl = nullptr;
        std::string what;
        const Value* slot = nullptr;
        for (std::size_t i = 0; i < net.parameters.size(); ++i) {
          if (net.parameters[i].name == name) {
            decl = &net.parameters[i];
            what = "parameter";
            slot = &parameter_values[i];
          }
        }
        for (std::size_t i = 0; i < nf && decl == nullptr; ++i) {
          if (net.facts[i].name == name) {
            decl = &net.facts[i];
            what = "fact";
            slots_of_fact[i].push_back(static_cast<std::uint32_t>(slots.size()));
            if (watchers_of_fact[i].empty() || watchers_of_fact[i].back() != t) watchers_of_fact[i].push_back(t);
          }
        }
        if (decl == nullptr) {
          problems.error(tr.where, "guard '" + tr.guard->text() + "' of transition '" + tr.id + "' reads '" + name +
                                       "', which is neither a parameter nor a fact of " + net_name);
        } else if (const auto expected = tr.guard->expected_type(s); expected && *expected != decl->type) {
          problems.error(tr.where, "guard '" + tr.guard->text() + "' of transition '" + tr.id + "' uses " + what +
                                       " '" + name + "' (" + std::string(to_string(decl->type)) + ") as a " +
                                       std::string(to_string(*expected)));
        }
        slots.push_back(slot);
      }
    }
    slot_begin.push_back(static_cast<std::uint32_t>(slots.size()));
  }
  fact_slot_begin.assign(1, 0);
  fact_watch_begin.assign(1, 0);
  for (std::size_t f = 0; f < nf; ++f) {
    fact_slots.insert(fact_slots.end(), slots_of_fact[f].begin(), slots_of_fact[f].end());
    fact_slot_begin.push_back(static_cast<std::uint32_t>(fact_slots.size()));
    fact_watchers.insert(fact_watchers.end(), watchers_of_fact[f].begin(), watchers_of_fact[f].end());
    fact_watch_begin.push_back(static_cast<std::uint32_t>(fact_watchers.size()));
    const VariableDecl& decl = net.facts[f];
    if (decl.default_value && type_of(*decl.default_value) != decl.type) {
      problems.error(decl.where, "default of fact '" + decl.name + "' is not a " + std::string(to_string(decl.type)));
    }
  }
}

void Engine::Impl::reset(Time start) {
  marking = net.initial_marking();
  now = start;
  instant_firings = 0;
  for (TransitionCode& tc : code) tc.enabled = false;
  ready.clear();
  for (auto& set : event_enabled) set.clear();
  timers.clear();
  for (FactId f = 0; f < net.facts.size(); ++f) {
    const auto& d = net.facts[f].default_value;
    fact_known[f] = d ? 1 : 0;
    fact_values[f] = d ? *d : Value{};
    for (std::uint32_t i = fact_slot_begin[f]; i < fact_slot_begin[f + 1]; ++i) {
      slots[fact_slots[i]] = d ? &fact_values[f] : nullptr;
    }
  }
  std::fill(reported_active.begin(), reported_active.end(), 0);
  for (PlaceFlags& f : place_flags) {
    if (f == PlaceFlags::bound_touched) f = PlaceFlags::bound;
  }
  touched_list.clear();
  for (PlaceIndex p = 0; p < marking.size(); ++p) {
    if (place_flags[p] == PlaceFlags::bound && marking[p] > 0) {
      place_flags[p] = PlaceFlags::bound_touched;
      touched_list.push_back(p);
    }
  }
  for (TransitionIndex t = 0; t < code.size(); ++t) update(t);
}

void Engine::Impl::set_fact(FactId f, Value value) {
  if (f >= net.facts.size()) throw std::invalid_argument("no fact with id " + std::to_string(f));
  const VariableDecl& decl = net.facts[f];
  if (type_of(value) != decl.type) {
    throw std::invalid_argument("fact '" + decl.name + "' is a " + std::string(to_string(decl.type)) +
                                ", cannot set it to the " + std::string(to_string(type_of(value))) + " " +
                                to_string(value));
  }
  fact_values[f] = std::move(value);
  fact_known[f] = 1;
  for (std::uint32_t i = fact_slot_begin[f]; i < fact_slot_begin[f + 1]; ++i) slots[fact_slots[i]] = &fact_values[f];
  for (std::uint32_t i = fact_watch_begin[f]; i < fact_watch_begin[f + 1]; ++i) update(fact_watchers[i]);
}

void Engine::Impl::report_livelock() {
  const std::size_t window = tail.size();
  const std::size_t length = std::min(window, instant_firings);
  // seq(i) = i-th of the last `length` firings, oldest first.
  auto seq = [&](std::size_t i) { return tail[(instant_firings - length + i) % window]; };
  // The smallest period of the last half of the tail: the first half may still hold the
  // firings that led into the loop.
  const std::size_t half = length / 2;
  std::size_t period = 0;
  for (std::size_t p = 1; p <= half / 2 && period == 0; ++p) {
    bool periodic = true;
    for (std::size_t i = length - half + p; i < length && periodic; ++i) periodic = seq(i) == seq(i - p);
    if (periodic) period = p;
  }
  result_filled = true;
  result.loop.clear();
  if (period != 0) {
    for (std::size_t i = length - period; i < length; ++i) result.loop.push_back(seq(i));
  } else {
    for (std::size_t i = 0; i < length; ++i) result.loop.push_back(seq(i));
    std::sort(result.loop.begin(), result.loop.end());
    result.loop.erase(std::unique(result.loop.begin(), result.loop.end()), result.loop.end());
  }
  result.status = StepStatus::livelock;
  std::string names;
  for (const TransitionIndex t : result.loop) names += (names.empty() ? "" : " -> ") + net.transition(t).id;
  result.error = "livelock in " + (net.id.empty() ? std::string("net") : "net '" + net.id + "'") + " at " +
                 seconds_text(now) + ": " + std::to_string(instant_firings) +
                 " firings at one instant without reaching a stable marking; " +
                 (period != 0 ? "the transitions " : "the transitions firing in the tail are ") + names +
                 (period != 0 ? " fire in a loop" : "");
  log->error("{}", result.error);
}

// --- Engine ---------------------------------------------------------------------------------

Engine::Engine(const PetriNet& net, const ParameterValues& parameters, EngineOptions options)
    : impl_(std::make_unique<Impl>(net, parameters, options)) {}
Engine::~Engine() = default;
Engine::Engine(Engine&&) noexcept = default;
Engine& Engine::operator=(Engine&&) noexcept = default;

// The supervisor's common call, without the event loops.
const StepResult& Engine::step(Time now) {
  Impl& m = *impl_;
  if (!m.start_step(now)) return m.result;
  if (m.idle_until(now)) {
    if (now > m.now) {
      m.now = now;
      m.instant_firings = 0;
    }
  } else {
    m.fire_until(now);
  }
  m.finish_step();  // bound places marked by a reset are reported by the first step
  return m.result;
}

const StepResult& Engine::step(Time now, std::span<const EventId> events) {
  Impl& m = *impl_;
  for (const EventId e : events) {
    if (e >= m.event_names.size()) throw std::invalid_argument("no event with id " + std::to_string(e));
  }
  if (!m.start_step(now)) return m.result;
  bool ok = m.advance(now);
  std::size_t i = 0;
  for (; i < events.size() && ok; ++i) ok = m.post(events[i], m.event_names[events[i]]);
  for (; i < events.size(); ++i) {
    m.result_filled = true;
    m.result.unconsumed_events.emplace_back(m.event_names[events[i]]);
  }
  m.finish_step();
  return m.result;
}

const StepResult& Engine::step(Time now, std::span<const std::string_view> events) {
  Impl& m = *impl_;
  if (!m.start_step(now)) return m.result;
  bool ok = m.advance(now);
  std::size_t i = 0;
  for (; i < events.size() && ok; ++i) {
    const auto it = m.event_ids.find(events[i]);
    if (it == m.event_ids.end()) {
      m.drop(events[i]);
    } else {
      ok = m.post(it->second, it->first);
    }
  }
  for (; i < events.size(); ++i) {
    m.result_filled = true;
    m.result.unconsumed_events.emplace_back(events[i]);
  }
  m.finish_step();
  return m.result;
}

const StepResult& Engine::step(Time now, std::initializer_list<std::string_view> events) {
  return step(now, std::span<const std::string_view>(events.begin(), events.size()));
}

std::optional<EventId> Engine::event_id(std::string_view name) const noexcept {
  const auto it = impl_->event_ids.find(name);
  if (it == impl_->event_ids.end()) return std::nullopt;
  return it->second;
}
std::string_view Engine::event_name(EventId id) const { return impl_->event_names.at(id); }
std::size_t Engine::event_count() const noexcept { return impl_->event_names.size(); }

void Engine::set_fact(std::string_view name, Value value) {
  const auto f = fact_id(name);
  if (!f) {
    throw std::invalid_argument("unknown fact '" + std::string(name) + "' in net '" + impl_->net.id + "'");
  }
  impl_->set_fact(*f, std::move(value));
}
void Engine::set_fact(FactId fact, Value value) { impl_->set_fact(fact, std::move(value)); }

void Engine::clear_fact(FactId f) {
  Impl& m = *impl_;
  if (f >= m.net.facts.size()) throw std::invalid_argument("no fact with id " + std::to_string(f));
  m.fact_known[f] = 0;
  for (std::uint32_t i = m.fact_slot_begin[f]; i < m.fact_slot_begin[f + 1]; ++i) m.slots[m.fact_slots[i]] = nullptr;
  for (std::uint32_t i = m.fact_watch_begin[f]; i < m.fact_watch_begin[f + 1]; ++i) m.update(m.fact_watchers[i]);
}

std::optional<FactId> Engine::fact_id(std::string_view name) const noexcept {
  const auto& facts = impl_->net.facts;
  for (FactId f = 0; f < facts.size(); ++f) {
    if (facts[f].name == name) return f;
  }
  return std::nullopt;
}

const Value* Engine::fact(FactId f) const {
  if (f >= impl_->net.facts.size()) throw std::invalid_argument("no fact with id " + std::to_string(f));
  return impl_->fact_known[f] != 0 ? &impl_->fact_values[f] : nullptr;
}

const Value& Engine::parameter(std::string_view name) const {
  const auto& params = impl_->net.parameters;
  for (std::size_t i = 0; i < params.size(); ++i) {
    if (params[i].name == name) return impl_->parameter_values[i];
  }
  throw std::invalid_argument("unknown parameter '" + std::string(name) + "'");
}

Time Engine::now() const noexcept { return impl_->now; }
std::span<const Tokens> Engine::marking() const noexcept { return impl_->marking; }
Tokens Engine::tokens(PlaceIndex place) const { return impl_->marking.at(place); }
bool Engine::is_enabled(TransitionIndex t) const { return impl_->code.at(t).enabled; }

std::optional<Time> Engine::next_deadline() const noexcept {
  if (impl_->timers.empty()) return std::nullopt;
  return impl_->timers.top().deadline;
}

OutcomeState Engine::outcome() const noexcept {
  const Impl& m = *impl_;
  OutcomeState best;
  for (const PlaceIndex p : m.outcome_places) {
    if (m.marking[p] == 0) continue;
    const Place& pl = m.net.places()[p];
    if (best.outcome == Outcome::fault) break;  // places are ascending: the first fault wins
    if (best.outcome == Outcome::success && pl.outcome != Outcome::fault) continue;
    best = OutcomeState{pl.outcome, p, pl.id, pl.outcome == Outcome::fault ? std::string_view(pl.fault_message)
                                                                            : std::string_view()};
  }
  return best;
}

std::vector<PlaceIndex> Engine::active_bindings() const {
  std::vector<PlaceIndex> out;
  for (PlaceIndex p = 0; p < impl_->marking.size(); ++p) {
    if (impl_->place_flags[p] != PlaceFlags::none && impl_->marking[p] > 0) out.push_back(p);
  }
  return out;
}

void Engine::add_observer(EngineObserver& observer) { impl_->observers.push_back(&observer); }
void Engine::remove_observer(const EngineObserver& observer) noexcept {
  auto& obs = impl_->observers;
  obs.erase(std::remove(obs.begin(), obs.end(), &observer), obs.end());
}

void Engine::reset(Time start) { impl_->reset(start); }
const PetriNet& Engine::net() const noexcept { return impl_->net; }
const EngineOptions& Engine::options() const noexcept { return impl_->options; }

}  // namespace tripodal
