// The fleet planner and its DDS connection (docs/distribution.md, "A fleet").
#include "tripodal/dds/fleet.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "tripodal/dds/endpoint.hpp"

namespace tripodal::dds {

namespace {

std::string fixed1(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

std::string join(const std::vector<std::string>& items, std::string_view sep) {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : std::string(sep)) + s;
  return out;
}

// Where a robot is taken to be for the nearest choice: its start, then its last unit's centroid.
struct Spot {
  double x_m = 0.0, y_m = 0.0;
};

// The balance behind assign_units and the reassignment: `order` (unit indices) largest first, each
// to the eligible robot of least load; within tie_m2 of it, the nearest; then the first.
std::vector<std::vector<std::size_t>> balance(std::vector<std::size_t> order, std::span<const FleetUnit> units,
                                              std::vector<double> load_m2, std::vector<Spot> at, std::span<const bool> eligible,
                                              double tie_m2) {
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return units[a].area_m2 > units[b].area_m2; });
  std::vector<std::vector<std::size_t>> out(load_m2.size());
  for (const std::size_t u : order) {
    double least = std::numeric_limits<double>::infinity();
    for (std::size_t r = 0; r < load_m2.size(); ++r) {
      if (eligible[r]) least = std::min(least, load_m2[r]);
    }
    std::size_t best = load_m2.size();
    double best_d = std::numeric_limits<double>::infinity();
    for (std::size_t r = 0; r < load_m2.size(); ++r) {
      if (!eligible[r] || load_m2[r] > least + tie_m2) continue;
      const double d = std::hypot(units[u].x_m - at[r].x_m, units[u].y_m - at[r].y_m);
      if (d < best_d) best = r, best_d = d;
    }
    out[best].push_back(u);
    load_m2[best] += units[u].area_m2;
    at[best] = {units[u].x_m, units[u].y_m};
  }
  return out;
}

}  // namespace

std::vector<std::vector<std::size_t>> assign_units(std::span<const FleetUnit> units, std::span<const FleetRobot> robots,
                                                   std::span<const bool> eligible, double tie_m2) {
  if (robots.empty()) throw std::invalid_argument("fleet: no robots to assign the units to");
  std::vector<bool> ok(robots.size(), true);
  if (!eligible.empty()) {
    if (eligible.size() != robots.size()) throw std::invalid_argument("fleet: eligible flags do not match the robots");
    std::copy(eligible.begin(), eligible.end(), ok.begin());
  }
  if (std::none_of(ok.begin(), ok.end(), [](bool b) { return b; })) throw std::invalid_argument("fleet: no eligible robot");
  for (const FleetUnit& u : units) {
    if (!(u.area_m2 > 0.0)) throw std::invalid_argument("fleet: unit '" + u.name + "' has area " + fixed1(u.area_m2) + " m2; expected > 0");
  }
  std::vector<std::size_t> order(units.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::vector<Spot> at;
  for (const FleetRobot& r : robots) at.push_back({r.x_m, r.y_m});
  const auto flags = std::make_unique<bool[]>(ok.size());  // std::vector<bool> has no span
  for (std::size_t i = 0; i < ok.size(); ++i) flags[i] = ok[i];
  return balance(std::move(order), units, std::vector<double>(robots.size(), 0.0), std::move(at), {flags.get(), ok.size()}, tie_m2);
}

// ---------------------------------------------------------------------------------------------
// FleetResult

std::size_t FleetResult::done() const noexcept {
  return static_cast<std::size_t>(std::count_if(units.begin(), units.end(), [](const FleetUnitResult& u) { return u.state == "done"; }));
}

std::string FleetResult::text() const {
  std::ostringstream s;
  for (const FleetUnitResult& u : units) {
    s << "unit " << u.name << " (" << u.task << "): " << u.state;
    if (u.state == "done") s << " by " << u.robot;
    if (u.state == "failed") s << " on " << u.robot << ": " << u.detail;
    if (u.state == "not done" && !u.robot.empty()) s << " (" << u.robot << " had it)";
    if (u.started_s >= 0.0) s << ", " << fixed1(u.started_s) << "-" << (u.finished_s >= 0.0 ? fixed1(u.finished_s) : "?") << " s";
    if (u.assigned.size() > 1) s << "; given to " << join(u.assigned, ", then ");
    s << '\n';
  }
  for (const FleetReassignment& r : reassignments) {
    s << "reassigned " << r.unit << " from " << r.from << " to " << r.to << " at " << fixed1(r.at_s) << " s: " << r.reason << '\n';
  }
  for (const std::string& r : silent) s << "silent: " << r << '\n';
  for (const std::string& r : back) s << "back: " << r << '\n';
  if (done_twice > 0 || cancelled > 0)
    s << "work done twice: " << done_twice << " units; cancelled mid-way: " << cancelled << '\n';
  const auto failed = std::count_if(units.begin(), units.end(), [](const FleetUnitResult& u) { return u.state == "failed"; });
  s << "fleet " << (succeeded ? "succeeded" : "did not finish") << ": " << done() << " of " << units.size() << " units done in "
    << fixed1(duration_s) << " s, " << reassignments.size() << (reassignments.size() == 1 ? " reassignment, " : " reassignments, ")
    << failed << " failed" << (reason.empty() ? "" : "; " + reason) << '\n';
  return s.str();
}

std::string FleetResult::json() const {
  // ordered_json: the keys in the order a reader expects them (the result first, then the units).
  using Json = nlohmann::ordered_json;
  Json out{{"succeeded", succeeded}, {"reason", reason}, {"duration_s", duration_s}};
  Json& list = out["units"] = Json::array();
  for (const FleetUnitResult& u : units) {
    list.push_back(Json{{"name", u.name}, {"task", u.task}, {"state", u.state}, {"robot", u.robot}, {"assigned", u.assigned},
                        {"started_s", u.started_s}, {"finished_s", u.finished_s}, {"detail", u.detail}});
  }
  Json& moves = out["reassignments"] = Json::array();
  for (const FleetReassignment& r : reassignments) {
    moves.push_back(Json{{"unit", r.unit}, {"from", r.from}, {"to", r.to}, {"at_s", r.at_s}, {"reason", r.reason}});
  }
  out["silent"] = silent;
  out["back"] = back;
  out["done_twice"] = done_twice;
  out["cancelled"] = cancelled;
  return out.dump(2) + "\n";
}

// ---------------------------------------------------------------------------------------------
// FleetPlanner

struct FleetPlanner::Robot {
  std::string name;
  Spot at;
  bool ready = false;
  bool alive = true;
  std::vector<std::size_t> queue;      // units not begun, in order
  std::optional<std::size_t> current;  // the unit in hand
  std::uint32_t command_id = 0;
  bool answered = false;
  bool paused = false;  // we asked it to pause (nothing to do: its simulation need not run)
  double sent_s = 0.0;   // the last (re)send of the command
  double given_s = 0.0;  // when the unit in hand was given
  std::optional<double> silent_since_s;  // silent, its units kept until the grace time ends
  std::string silent_reason;
  std::optional<std::size_t> lost;  // the unit it had in hand when declared silent
  double declared_s = 0.0;
  bool gone = false;  // its process ended
};

struct FleetPlanner::Unit {
  enum class State { waiting, running, done, failed } state = State::waiting;
  std::string robot;
  std::vector<std::string> assigned;
  double started_s = -1.0, finished_s = -1.0;
  std::string detail;
};

FleetPlanner::FleetPlanner(std::vector<FleetRobot> robots, std::vector<FleetUnit> units, const Clock& clock, FleetOptions options)
    : clock_(clock), options_(options), start_(clock.now()), robot_info_(std::move(robots)), unit_info_(std::move(units)) {
  if (unit_info_.empty()) throw std::invalid_argument("fleet: the task has no units to share");
  std::set<std::string, std::less<>> names;
  for (const FleetRobot& r : robot_info_) {
    if (!names.insert(r.name).second) throw std::invalid_argument("fleet: robot '" + r.name + "' is listed twice");
  }
  names.clear();
  for (const FleetUnit& u : unit_info_) {
    if (!names.insert(u.name).second) throw std::invalid_argument("fleet: unit '" + u.name + "' is listed twice");
  }
  const auto plan = assign_units(unit_info_, robot_info_);
  units_.resize(unit_info_.size());
  for (std::size_t i = 0; i < robot_info_.size(); ++i) {
    auto r = std::make_unique<Robot>();
    r->name = robot_info_[i].name;
    r->at = {robot_info_[i].x_m, robot_info_[i].y_m};
    r->queue = plan[i];
    std::vector<std::string> mine;
    for (const std::size_t u : plan[i]) {
      units_[u].assigned.push_back(r->name);
      mine.push_back(unit_info_[u].name);
    }
    note(r->name + " gets " + (mine.empty() ? std::string("nothing") : join(mine, ", ")));
    robots_.push_back(std::move(r));
  }
}

FleetPlanner::~FleetPlanner() = default;

double FleetPlanner::seconds() const noexcept { return to_seconds(clock_.now() - start_); }

FleetPlanner::Robot* FleetPlanner::find(std::string_view robot) {
  for (auto& r : robots_) {
    if (r->name == robot) return r.get();
  }
  return nullptr;
}

const FleetPlanner::Robot* FleetPlanner::find(std::string_view robot) const {
  for (const auto& r : robots_) {
    if (r->name == robot) return r.get();
  }
  return nullptr;
}

void FleetPlanner::note(std::string line) { log_.push_back(fixed1(seconds()) + " s  " + std::move(line)); }

std::vector<std::string> FleetPlanner::take_log() {
  std::vector<std::string> out;
  out.swap(log_);
  return out;
}

std::vector<std::string> FleetPlanner::queue_of(std::string_view robot) const {
  std::vector<std::string> out;
  const Robot* r = find(robot);
  if (r == nullptr) return out;
  if (r->current) out.push_back(unit_info_[*r->current].name);
  for (const std::size_t u : r->queue) out.push_back(unit_info_[u].name);
  return out;
}

bool FleetPlanner::alive(std::string_view robot) const {
  const Robot* r = find(robot);
  return r != nullptr && r->alive;
}

bool FleetPlanner::ready(std::string_view robot) const {
  const Robot* r = find(robot);
  return r != nullptr && r->ready;
}

void FleetPlanner::robot_ready(std::string_view robot) {
  Robot* r = find(robot);
  if (r == nullptr || !r->alive || r->ready) return;
  r->ready = true;
  note(r->name + " is on DDS");
}

void FleetPlanner::finish_unit(Robot& r, bool ok, std::string_view detail) {
  Unit& u = units_[*r.current];
  if (u.state == Unit::State::done) {  // another robot finished it first (a robot back from a partition)
    if (ok) {
      ++done_twice_;
      note(r.name + " finished " + unit_info_[*r.current].name + ", which " + u.robot + " had done: done twice");
    }
    r.current.reset();
    return;
  }
  if (ok) {
    // One record of what is done: any other robot on this unit stops.
    for (auto& other : robots_) {
      if (other.get() == &r || other->current != r.current) continue;
      ++cancelled_;
      note(other->name + " is told to cancel " + unit_info_[*r.current].name + ": " + r.name + " finished it");
      pending_.push_back({other->name, next_id_++, "cancel", {}, unit_info_[*r.current].name});
      other->current.reset();
    }
  }
  u.state = ok ? Unit::State::done : Unit::State::failed;
  u.robot = r.name;
  u.finished_s = seconds();
  u.detail = std::string(detail);
  note(r.name + (ok ? " finished " : " failed ") + unit_info_[*r.current].name + (ok ? "" : ": " + u.detail));
  r.current.reset();
}

void FleetPlanner::robot_event(std::string_view robot, std::string_view kind, std::string_view source, std::string_view detail) {
  Robot* r = find(robot);
  if (r == nullptr || !r->alive || !r->current) return;
  const std::string& task = unit_info_[*r->current].task;
  const bool about_task = detail.substr(0, task.size()) == task;
  if (kind == "command_accepted" || kind == "command_refused") {
    if (source != "task_command/" + std::to_string(r->command_id) || r->answered) return;
    r->answered = true;
    if (kind == "command_refused") finish_unit(*r, false, "refused: " + std::string(detail));
  } else if (kind == "task_started" && about_task) {
    Unit& u = units_[*r->current];
    if (u.started_s < 0.0) u.started_s = seconds();
    r->answered = true;  // the answer may have been lost; the task runs
  } else if (kind == "task_succeeded" && about_task) {
    finish_unit(*r, true, {});
  } else if (kind == "task_failed" && about_task) {
    std::string_view why = detail.substr(task.size());
    if (why.substr(0, 2) == ": ") why.remove_prefix(2);
    finish_unit(*r, false, why);
  }
}

void FleetPlanner::redistribute(std::vector<std::size_t> units, const std::string& from, const std::string& reason) {
  if (units.empty()) return;
  std::vector<double> load(robots_.size(), 0.0);
  std::vector<Spot> at(robots_.size());
  const std::unique_ptr<bool[]> eligible(new bool[robots_.size()]);
  bool any = false;
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    const Robot& r = *robots_[i];
    eligible[i] = r.alive;
    any = any || r.alive;
    at[i] = r.at;
    if (r.current) load[i] += unit_info_[*r.current].area_m2;
    for (const std::size_t u : r.queue) load[i] += unit_info_[u].area_m2;
    const std::size_t last = !r.queue.empty() ? r.queue.back() : r.current.value_or(unit_info_.size());
    if (last < unit_info_.size()) at[i] = {unit_info_[last].x_m, unit_info_[last].y_m};
  }
  if (!any) {
    std::vector<std::string> names;
    names.reserve(units.size());
    for (const std::size_t u : units) names.push_back(unit_info_[u].name);
    note("no robot left for " + join(names, ", "));
    return;
  }
  const auto plan = balance(units, unit_info_, std::move(load), std::move(at), {eligible.get(), robots_.size()}, 1e-6);
  // Recorded in the order the balance gave them out (largest first), whoever took them.
  std::stable_sort(units.begin(), units.end(), [&](std::size_t a, std::size_t b) { return unit_info_[a].area_m2 > unit_info_[b].area_m2; });
  for (const std::size_t u : units) {
    for (std::size_t i = 0; i < robots_.size(); ++i) {
      if (std::find(plan[i].begin(), plan[i].end(), u) == plan[i].end()) continue;
      Robot& to = *robots_[i];
      to.queue.push_back(u);
      units_[u].assigned.push_back(to.name);
      units_[u].state = Unit::State::waiting;
      reassignments_.push_back({unit_info_[u].name, from, to.name, seconds(), reason});
      note("reassigned " + unit_info_[u].name + " from " + from + " to " + to.name);
    }
  }
}

void FleetPlanner::robot_silent(std::string_view robot, std::string_view reason) {
  Robot* r = find(robot);
  if (r == nullptr || !r->alive || r->silent_since_s) return;
  r->silent_since_s = seconds();
  r->silent_reason = std::string(reason);
  if (options_.silence_grace.count() <= 0) {
    declare_silent(*r);
  } else {
    note(r->name + " is silent (" + r->silent_reason + "): its units wait " + fixed1(to_seconds(options_.silence_grace)) +
         " s for it");
  }
}

void FleetPlanner::declare_silent(Robot& r) {
  r.alive = false;
  r.declared_s = seconds();
  const std::string why = r.name + " went silent (" + r.silent_reason + ")";
  silent_.push_back(r.name + " at " + fixed1(seconds()) + " s: " + r.silent_reason);
  note(why);
  std::vector<std::size_t> left;
  r.lost = r.current;
  if (r.current) left.push_back(*r.current);
  left.insert(left.end(), r.queue.begin(), r.queue.end());
  r.current.reset();
  r.queue.clear();
  redistribute(std::move(left), r.name, why);
}

void FleetPlanner::robot_gone(std::string_view robot) {
  Robot* r = find(robot);
  if (r == nullptr) return;
  r->gone = true;
  r->lost.reset();
}

void FleetPlanner::robot_back(std::string_view robot) {
  Robot* r = find(robot);
  if (r == nullptr || r->gone || !r->silent_since_s) return;
  const double away = seconds() - *r->silent_since_s;
  r->silent_since_s.reset();
  if (r->alive) {
    note(r->name + " is back after " + fixed1(away) + " s, within the grace time: it keeps its units");
    return;
  }
  r->alive = true;
  r->answered = true;
  back_.push_back(r->name + " at " + fixed1(seconds()) + " s (silent " + fixed1(away) + " s)");
  if (!r->lost) {
    note(r->name + " is back after " + fixed1(away) + " s");
    return;
  }
  const std::size_t lost = *r->lost;
  r->lost.reset();
  Unit& u = units_[lost];
  const std::string& name = unit_info_[lost].name;
  r->current = lost;  // it went on with it: nothing new for it before it says how that ended
  r->given_s = seconds();
  if (u.state == Unit::State::done || u.state == Unit::State::failed) {
    note(r->name + " is back after " + fixed1(away) + " s, still on " + name + ", which " + u.robot + " has ended");
    return;
  }
  for (auto& other : robots_) {
    auto at = std::find(other->queue.begin(), other->queue.end(), lost);
    if (at == other->queue.end()) continue;
    other->queue.erase(at);
    u.assigned.push_back(r->name);
    u.state = Unit::State::running;
    u.robot = r->name;
    reassignments_.push_back({name, other->name, r->name, seconds(), r->name + " is back with it in hand"});
    note(r->name + " is back after " + fixed1(away) + " s with " + name + " in hand: taken back from " + other->name +
         "'s queue");
    return;
  }
  note(r->name + " is back after " + fixed1(away) + " s with " + name + " in hand, which " + u.robot +
       " runs too: the first to finish it keeps it");
}

void FleetPlanner::take_queued(Robot& idle) {
  Robot* from = nullptr;
  double most_m2 = 0.0;
  for (auto& rp : robots_) {
    if (rp.get() == &idle || !rp->alive || rp->queue.empty()) continue;
    double queued_m2 = 0.0;
    for (const std::size_t u : rp->queue) queued_m2 += unit_info_[u].area_m2;
    if (queued_m2 > most_m2) from = rp.get(), most_m2 = queued_m2;
  }
  if (from == nullptr) return;
  const std::size_t u = from->queue.back();  // the one it would have begun last
  from->queue.pop_back();
  idle.queue.push_back(u);
  units_[u].assigned.push_back(idle.name);
  const std::string why = idle.name + " had nothing left to do";
  reassignments_.push_back({unit_info_[u].name, from->name, idle.name, seconds(), why});
  note("reassigned " + unit_info_[u].name + " from " + from->name + " to " + idle.name + ": " + why);
}

std::vector<FleetCommand> FleetPlanner::poll() {
  std::vector<FleetCommand> out;
  out.swap(pending_);
  const double now = seconds();
  for (auto& rp : robots_) {
    if (rp->alive && rp->silent_since_s && now - *rp->silent_since_s >= to_seconds(options_.silence_grace)) declare_silent(*rp);
  }
  for (auto& rp : robots_) {
    if (rp->alive && !rp->ready && now >= to_seconds(options_.startup_timeout)) {
      robot_silent(rp->name, "not on DDS within " + fixed1(to_seconds(options_.startup_timeout)) + " s");
    }
  }
  for (auto& rp : robots_) {
    Robot& r = *rp;
    if (!r.alive || !r.ready || r.silent_since_s) continue;
    if (!r.current && r.queue.empty() && options_.take_when_idle) take_queued(r);
    if (!r.current && r.queue.empty() && !r.paused && options_.pause_idle) {
      r.paused = true;
      note(r.name + " has nothing left to do: paused");
      out.push_back({r.name, next_id_++, "pause", {}, {}});
    } else if (!r.current && !r.queue.empty()) {
      if (r.paused) {
        r.paused = false;
        out.push_back({r.name, next_id_++, "resume", {}, {}});
      }
      r.current = r.queue.front();
      r.queue.erase(r.queue.begin());
      r.command_id = next_id_++;
      r.answered = false;
      r.sent_s = now;
      r.given_s = now;
      Unit& u = units_[*r.current];
      u.state = Unit::State::running;
      u.robot = r.name;
      u.started_s = -1.0;
      r.at = {unit_info_[*r.current].x_m, unit_info_[*r.current].y_m};
      note(r.name + " starts " + unit_info_[*r.current].name + ": \"" + unit_info_[*r.current].task + "\"");
      out.push_back({r.name, r.command_id, "start", unit_info_[*r.current].task, unit_info_[*r.current].name});
    } else if (r.current && !r.answered && now - r.sent_s >= to_seconds(options_.answer_timeout)) {
      r.sent_s = now;
      note(r.name + ": no answer to command " + std::to_string(r.command_id) + ", sent again");
      out.push_back({r.name, r.command_id, "start", unit_info_[*r.current].task, unit_info_[*r.current].name});
    }
  }
  return out;
}

bool FleetPlanner::finished() const noexcept {
  const bool all_ended = std::all_of(units_.begin(), units_.end(), [](const Unit& u) {
    return u.state == Unit::State::done || u.state == Unit::State::failed;
  });
  const bool none_alive = std::none_of(robots_.begin(), robots_.end(), [](const auto& r) { return r->alive; });
  return all_ended || none_alive;
}

FleetResult FleetPlanner::result() const {
  FleetResult res;
  res.duration_s = seconds();
  res.reassignments = reassignments_;
  res.silent = silent_;
  res.back = back_;
  res.done_twice = done_twice_;
  res.cancelled = cancelled_;
  std::vector<std::string> missing, failed;
  for (std::size_t i = 0; i < units_.size(); ++i) {
    const Unit& u = units_[i];
    FleetUnitResult r;
    r.name = unit_info_[i].name;
    r.task = unit_info_[i].task;
    r.robot = u.robot;
    r.assigned = u.assigned;
    r.started_s = u.started_s;
    r.finished_s = u.finished_s;
    r.detail = u.detail;
    switch (u.state) {
      case Unit::State::done: r.state = "done"; break;
      case Unit::State::failed: r.state = "failed"; failed.push_back(r.name); break;
      default: r.state = "not done"; missing.push_back(r.name); break;
    }
    res.units.push_back(std::move(r));
  }
  res.succeeded = missing.empty() && failed.empty();
  if (!failed.empty()) res.reason = "failed: " + join(failed, ", ");
  if (!missing.empty()) {
    const bool none_alive = std::none_of(robots_.begin(), robots_.end(), [](const auto& r) { return r->alive; });
    res.reason += (res.reason.empty() ? "" : "; ") + std::string("not done: ") + join(missing, ", ") +
                  (none_alive ? " (no robot left)" : "");
  }
  return res;
}

std::optional<double> FleetPlanner::busy_since_s(std::string_view robot) const {
  const Robot* r = find(robot);
  if (r == nullptr || !r->current) return std::nullopt;
  return r->given_s;
}

double FleetPlanner::elapsed_s() const noexcept { return seconds(); }

// ---------------------------------------------------------------------------------------------
// DdsFleet

struct DdsFleet::Impl {
  struct Arrival {
    std::size_t robot = 0;
    bool silent = false;
    bool back = false;
    msg::Event event;
  };
  struct Link {
    std::string name;
    std::optional<Publisher<msg::TaskCommand>> task;
    std::optional<Subscriber<msg::Event>> events;
    bool ready = false;
  };

  FleetPlanner& planner;
  std::unique_ptr<Participant> participant;
  // Filled on Cyclone DDS threads, emptied in update(): declared before the links, whose
  // callbacks write into it, so that it outlives them.
  std::mutex inbox_mutex;
  std::vector<Arrival> inbox;
  std::vector<std::unique_ptr<Link>> links;

  Impl(FleetPlanner& p, std::span<const FleetRobot> robots, const DdsFleetOptions& o) : planner(p) {
    ParticipantOptions po;
    po.domain_id = o.domain_id;
    po.network = o.network;
    po.participant_lease = o.participant_lease;
    po.security = o.security;
    participant = std::make_unique<Participant>(po);
    for (std::size_t i = 0; i < robots.size(); ++i) {
      auto l = std::make_unique<Link>();
      l->name = robots[i].name;
      const std::string& ns = robots[i].ns.empty() ? robots[i].name : robots[i].ns;
      // A resume and a start go together: a history of one could drop the first before it is
      // acknowledged. (The robot's reader hands each sample to a callback as it arrives.)
      Qos q = qos_for(TopicKind::command, Role::publisher);
      q.depth = 16;
      l->task.emplace(*participant, ros_topic("tripodal/task", ns), EndpointOptions{.kind = TopicKind::command, .qos = q});
      EndpointOptions eo{.kind = TopicKind::event};
      eo.on_status = [this, i](const StatusEvent& s) {
        const bool lost = s.kind == StatusKind::liveliness_lost && s.current_count == 0;
        const bool regained =
            (s.kind == StatusKind::liveliness_regained || s.kind == StatusKind::publication_matched) && s.current_count > 0;
        if (!lost && !regained) return;
        std::lock_guard lock(inbox_mutex);
        inbox.push_back({i, lost, regained, {}});
      };
      l->events.emplace(*participant, ros_topic("tripodal/events", ns), eo, [this, i](const msg::Event& e) {
        std::lock_guard lock(inbox_mutex);
        inbox.push_back({i, false, false, e});
      });
      links.push_back(std::move(l));
    }
  }

  ~Impl() { links.clear(); }  // no more callbacks before the inbox goes
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  void update() {
    // Ready once our command writer and the robot's event writer have met: what we send reaches it
    // and its answer (and later its silence) reaches us.
    for (auto& l : links) {
      if (!l->ready && l->task->matched_subscribers() > 0 && l->events->matched_publishers() > 0) {
        l->ready = true;
        planner.robot_ready(l->name);
      }
    }
    std::vector<Arrival> arrived;
    {
      std::lock_guard lock(inbox_mutex);
      arrived.swap(inbox);
    }
    for (const Arrival& a : arrived) {
      const std::string& name = links[a.robot]->name;
      if (a.silent) planner.robot_silent(name, "liveliness lost");
      else if (a.back)
        planner.robot_back(name);
      else planner.robot_event(name, a.event.kind, a.event.source, a.event.detail);
    }
    for (const FleetCommand& c : planner.poll()) {
      for (auto& l : links) {
        if (l->name != c.robot) continue;
        // robot empty: any robot; the namespace already picks this one
        l->task->publish(msg::TaskCommand{ros_time(planner.elapsed_s()), "", c.id, c.command, c.task});
      }
    }
  }
};

DdsFleet::DdsFleet(FleetPlanner& planner, std::span<const FleetRobot> robots, const DdsFleetOptions& options)
    : impl_(std::make_unique<Impl>(planner, robots, options)) {}

DdsFleet::~DdsFleet() = default;

void DdsFleet::update() { impl_->update(); }

}  // namespace tripodal::dds
