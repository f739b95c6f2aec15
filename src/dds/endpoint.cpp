// Typed publishers and subscribers on Cyclone DDS's C API, with their listeners.
#include "tripodal/dds/endpoint.hpp"

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>

#include <array>
#include <mutex>
#include <thread>
#include <utility>

#include "node_graph.hpp"
#include "qos_c.hpp"
#include "type_support.hpp"

namespace tripodal::dds {

std::string ros_topic(std::string_view name, std::string_view ns) {
  auto strip = [](std::string_view s) {
    while (!s.empty() && s.front() == '/') s.remove_prefix(1);
    while (!s.empty() && s.back() == '/') s.remove_suffix(1);
    return s;
  };
  name = strip(name);
  ns = strip(ns);
  std::string topic = "rt/";
  if (!ns.empty()) {
    topic += ns;
    topic += '/';
  }
  topic += name;
  return topic;
}

std::string_view to_string(StatusKind kind) {
  switch (kind) {
    case StatusKind::liveliness_lost: return "liveliness_lost";
    case StatusKind::liveliness_regained: return "liveliness_regained";
    case StatusKind::deadline_missed: return "deadline_missed";
    case StatusKind::publication_matched: return "publication_matched";
    case StatusKind::subscription_matched: return "subscription_matched";
    case StatusKind::own_liveliness_lost: return "own_liveliness_lost";
  }
  return "?";
}

namespace detail {

struct ListenerDeleter {
  void operator()(dds_listener_t* l) const noexcept { dds_delete_listener(l); }
};

struct EndpointCore {
  std::string topic_name;
  Qos qos;
  StatusCallback on_status;
  std::function<void()> on_data;  // a subscriber's typed drain, when it has a data callback
  std::mutex data_mutex;          // one drain at a time: the user's callback never runs concurrently
  dds_entity_t topic = 0;
  dds_entity_t entity = 0;  // the writer or the reader
  dds_entity_t waitset = 0;
  dds_entity_t read_condition = 0;
  std::shared_ptr<NodeGraph> graph;  // told of the endpoint, for ros_discovery_info

  EndpointCore() = default;
  EndpointCore(const EndpointCore&) = delete;
  EndpointCore& operator=(const EndpointCore&) = delete;
  ~EndpointCore() {
    // Deleting the reader or writer waits for its listener callbacks in progress, which use this
    // object: so it goes first.
    if (graph && entity > 0) graph->remove(entity);
    if (waitset > 0) dds_delete(waitset);
    if (entity > 0) dds_delete(entity);
    if (topic > 0) dds_delete(topic);
  }

  std::string where(std::string_view op) const { return "dds: " + std::string(op) + " on '" + topic_name + "'"; }

  void report(StatusKind kind, std::int32_t total, std::int32_t current) const {
    if (on_status) on_status(StatusEvent{kind, topic_name, total, current, std::chrono::steady_clock::now()});
  }
};

namespace {

EndpointCore* core_of(void* arg) { return static_cast<EndpointCore*>(arg); }

void on_data_available(dds_entity_t, void* arg) {
  auto* core = core_of(arg);
  if (core->on_data) {
    std::lock_guard lock(core->data_mutex);
    core->on_data();
  }
}
void on_liveliness_changed(dds_entity_t, const dds_liveliness_changed_status_t status, void* arg) {
  // Each change carries how many writers became alive or not alive (a deleted writer counts as
  // not alive then gone); one event per direction.
  auto* core = core_of(arg);
  if (status.not_alive_count_change > 0 || status.alive_count_change < 0) {
    core->report(StatusKind::liveliness_lost, static_cast<std::int32_t>(status.not_alive_count),
                 static_cast<std::int32_t>(status.alive_count));
  }
  if (status.alive_count_change > 0) {
    core->report(StatusKind::liveliness_regained, static_cast<std::int32_t>(status.not_alive_count),
                 static_cast<std::int32_t>(status.alive_count));
  }
}
void on_requested_deadline_missed(dds_entity_t, const dds_requested_deadline_missed_status_t status, void* arg) {
  core_of(arg)->report(StatusKind::deadline_missed, static_cast<std::int32_t>(status.total_count), 0);
}
void on_offered_deadline_missed(dds_entity_t, const dds_offered_deadline_missed_status_t status, void* arg) {
  core_of(arg)->report(StatusKind::deadline_missed, static_cast<std::int32_t>(status.total_count), 0);
}
void on_subscription_matched(dds_entity_t, const dds_subscription_matched_status_t status, void* arg) {
  core_of(arg)->report(StatusKind::publication_matched, static_cast<std::int32_t>(status.total_count),
                       static_cast<std::int32_t>(status.current_count));
}
void on_publication_matched(dds_entity_t, const dds_publication_matched_status_t status, void* arg) {
  core_of(arg)->report(StatusKind::subscription_matched, static_cast<std::int32_t>(status.total_count),
                       static_cast<std::int32_t>(status.current_count));
}
void on_liveliness_lost(dds_entity_t, const dds_liveliness_lost_status_t status, void* arg) {
  core_of(arg)->report(StatusKind::own_liveliness_lost, static_cast<std::int32_t>(status.total_count), 0);
}

std::unique_ptr<EndpointCore> make_core(Participant& participant, std::string topic_name,
                                        const dds_topic_descriptor_t* descriptor, const EndpointOptions& options,
                                        Role role, bool with_data_callback) {
  auto core = std::make_unique<EndpointCore>();
  core->topic_name = std::move(topic_name);
  core->qos = options.qos ? *options.qos : qos_for(options.kind, role);
  core->on_status = options.on_status;
  if (core->topic_name.empty()) throw DdsError("dds: a topic needs a name (ros_topic(\"cmd_vel\") gives \"rt/cmd_vel\")");

  core->topic = dds_create_topic(participant.handle(), descriptor, core->topic_name.c_str(), nullptr, nullptr);
  check(core->topic, core->where(std::string("dds_create_topic of type ") + descriptor->m_typename));

  const auto qos = to_dds_qos(core->qos);
  const std::unique_ptr<dds_listener_t, ListenerDeleter> listener(dds_create_listener(core.get()));
  if (role == Role::subscriber) {
    dds_lset_liveliness_changed(listener.get(), on_liveliness_changed);
    dds_lset_requested_deadline_missed(listener.get(), on_requested_deadline_missed);
    dds_lset_subscription_matched(listener.get(), on_subscription_matched);
    if (with_data_callback) dds_lset_data_available(listener.get(), on_data_available);
    core->entity = dds_create_reader(participant.handle(), core->topic, qos.get(), listener.get());
    check(core->entity, core->where("dds_create_reader"));
  } else {
    dds_lset_offered_deadline_missed(listener.get(), on_offered_deadline_missed);
    dds_lset_publication_matched(listener.get(), on_publication_matched);
    dds_lset_liveliness_lost(listener.get(), on_liveliness_lost);
    core->entity = dds_create_writer(participant.handle(), core->topic, qos.get(), listener.get());
    check(core->entity, core->where("dds_create_writer"));
  }
  core->graph = participant.graph();
  core->graph->add(core->entity, role == Role::subscriber);
  return core;
}

// Polls a matched count: matching is asynchronous (discovery) and has no blocking wait in the API.
template <class Count>
bool wait_for_count(Count count, std::size_t wanted, std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (count() < wanted) {
    if (std::chrono::steady_clock::now() >= until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

template <class T>
std::vector<T> take_samples(const EndpointCore& core, std::size_t max) {
  using C = typename TypeSupport<T>::C;
  std::vector<T> out;
  constexpr std::size_t kBatch = 16;
  std::array<void*, kBatch> samples{};
  std::array<dds_sample_info_t, kBatch> infos{};
  while (out.size() < max) {
    samples.fill(nullptr);  // null: Cyclone lends its own samples, returned below
    const auto wanted = static_cast<uint32_t>(std::min(kBatch, max - out.size()));
    const dds_return_t n = dds_take(core.entity, samples.data(), infos.data(), wanted, wanted);
    check(n, core.where("dds_take"));
    for (dds_return_t i = 0; i < n; ++i) {
      // Invalid samples only carry an instance state change (a writer left).
      if (infos[static_cast<std::size_t>(i)].valid_data) {
        out.push_back(TypeSupport<T>::from_c(*static_cast<const C*>(samples[static_cast<std::size_t>(i)])));
      }
    }
    if (n > 0) dds_return_loan(core.entity, samples.data(), n);
    if (static_cast<uint32_t>(n) < wanted) break;
  }
  return out;
}

}  // namespace
}  // namespace detail

// --- Publisher -----------------------------------------------------------------------------

template <Message T>
Publisher<T>::Publisher(Participant& participant, const std::string& topic, const EndpointOptions& options)
    : core_(detail::make_core(participant, topic, detail::TypeSupport<T>::descriptor(), options,
                              Role::publisher, false)) {}

template <Message T>
Publisher<T>::~Publisher() = default;
template <Message T>
Publisher<T>::Publisher(Publisher&&) noexcept = default;
template <Message T>
Publisher<T>& Publisher<T>::operator=(Publisher&&) noexcept = default;

template <Message T>
void Publisher<T>::publish(const T& message) {
  using Support = detail::TypeSupport<T>;
  if constexpr (requires { typename Support::Scratch; }) {
    typename Support::Scratch scratch;  // what the C view points into (a string sequence's pointers)
    const auto sample = Support::to_c(message, scratch);
    detail::check(dds_write(core_->entity, &sample), core_->where("dds_write"));
  } else {
    const auto sample = Support::to_c(message);
    detail::check(dds_write(core_->entity, &sample), core_->where("dds_write"));
  }
}

template <Message T>
void Publisher<T>::assert_liveliness() {
  detail::check(dds_assert_liveliness(core_->entity), core_->where("dds_assert_liveliness"));
}

template <Message T>
bool Publisher<T>::wait_for_acknowledgments(std::chrono::milliseconds timeout) {
  const dds_return_t rc =
      dds_wait_for_acks(core_->entity, std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count());
  if (rc == DDS_RETCODE_TIMEOUT) return false;
  detail::check(rc, core_->where("dds_wait_for_acks"));
  return true;
}

template <Message T>
std::size_t Publisher<T>::matched_subscribers() const {
  dds_publication_matched_status_t status{};
  detail::check(dds_get_publication_matched_status(core_->entity, &status), core_->where("matched status"));
  return status.current_count;
}

template <Message T>
bool Publisher<T>::wait_for_subscribers(std::size_t count, std::chrono::milliseconds timeout) const {
  return detail::wait_for_count([this] { return matched_subscribers(); }, count, timeout);
}

template <Message T>
const std::string& Publisher<T>::topic() const noexcept { return core_->topic_name; }
template <Message T>
const Qos& Publisher<T>::qos() const noexcept { return core_->qos; }

// --- Subscriber ----------------------------------------------------------------------------

template <Message T>
Subscriber<T>::Subscriber(Participant& participant, const std::string& topic, const EndpointOptions& options,
                          DataCallback on_data) {
  const bool with_callback = static_cast<bool>(on_data);
  core_ = detail::make_core(participant, topic, detail::TypeSupport<T>::descriptor(), options,
                            Role::subscriber, false);
  if (with_callback) {
    // Installed after creation, then the listener enabled: the reader was made without a data
    // callback so that none runs before on_data is set.
    detail::EndpointCore* raw = core_.get();
    raw->on_data = [raw, callback = std::move(on_data)] {
      for (const T& sample : detail::take_samples<T>(*raw, 1024)) callback(sample);
    };
    const std::unique_ptr<dds_listener_t, detail::ListenerDeleter> listener(dds_create_listener(raw));
    dds_lset_liveliness_changed(listener.get(), detail::on_liveliness_changed);
    dds_lset_requested_deadline_missed(listener.get(), detail::on_requested_deadline_missed);
    dds_lset_subscription_matched(listener.get(), detail::on_subscription_matched);
    dds_lset_data_available(listener.get(), detail::on_data_available);
    detail::check(dds_set_listener(raw->entity, listener.get()), raw->where("dds_set_listener"));
    // Samples that came before the listener was set raise no new data-available: drain them.
    std::lock_guard lock(raw->data_mutex);
    raw->on_data();
  } else {
    core_->read_condition = dds_create_readcondition(core_->entity, DDS_ANY_STATE);
    detail::check(core_->read_condition, core_->where("dds_create_readcondition"));
    core_->waitset = dds_create_waitset(participant.handle());
    detail::check(core_->waitset, core_->where("dds_create_waitset"));
    detail::check(dds_waitset_attach(core_->waitset, core_->read_condition, 0), core_->where("dds_waitset_attach"));
  }
}

template <Message T>
Subscriber<T>::~Subscriber() = default;
template <Message T>
Subscriber<T>::Subscriber(Subscriber&&) noexcept = default;
template <Message T>
Subscriber<T>& Subscriber<T>::operator=(Subscriber&&) noexcept = default;

template <Message T>
std::vector<T> Subscriber<T>::take(std::size_t max) {
  return detail::take_samples<T>(*core_, max);
}

template <Message T>
std::optional<T> Subscriber<T>::take_one(std::chrono::milliseconds timeout) {
  if (core_->waitset == 0) throw DdsError(core_->where("take_one") + ": this subscriber has a data callback");
  const auto until = std::chrono::steady_clock::now() + timeout;
  while (true) {
    auto samples = detail::take_samples<T>(*core_, 1);
    if (!samples.empty()) return std::move(samples.front());
    const auto left = until - std::chrono::steady_clock::now();
    if (left <= std::chrono::nanoseconds::zero()) return std::nullopt;
    detail::check(dds_waitset_wait(core_->waitset, nullptr, 0,
                                   std::chrono::duration_cast<std::chrono::nanoseconds>(left).count()),
                  core_->where("dds_waitset_wait"));
  }
}

template <Message T>
std::vector<std::vector<std::uint8_t>> Subscriber<T>::take_serialized(std::size_t max) {
  std::vector<std::vector<std::uint8_t>> out;
  constexpr std::size_t kBatch = 16;
  std::array<ddsi_serdata*, kBatch> data{};
  std::array<dds_sample_info_t, kBatch> infos{};
  while (out.size() < max) {
    const auto wanted = static_cast<uint32_t>(std::min(kBatch, max - out.size()));
    const dds_return_t n = dds_takecdr(core_->entity, data.data(), wanted, infos.data(), DDS_ANY_STATE);
    detail::check(n, core_->where("dds_takecdr"));
    for (dds_return_t i = 0; i < n; ++i) {
      ddsi_serdata* d = data[static_cast<std::size_t>(i)];
      if (infos[static_cast<std::size_t>(i)].valid_data) {
        std::vector<std::uint8_t> bytes(ddsi_serdata_size(d));
        ddsi_serdata_to_ser(d, 0, bytes.size(), bytes.data());
        out.push_back(std::move(bytes));
      }
      ddsi_serdata_unref(d);
    }
    if (static_cast<uint32_t>(n) < wanted) break;
  }
  return out;
}

template <Message T>
std::size_t Subscriber<T>::matched_publishers() const {
  dds_subscription_matched_status_t status{};
  detail::check(dds_get_subscription_matched_status(core_->entity, &status), core_->where("matched status"));
  return status.current_count;
}

template <Message T>
bool Subscriber<T>::wait_for_publishers(std::size_t count, std::chrono::milliseconds timeout) const {
  return detail::wait_for_count([this] { return matched_publishers(); }, count, timeout);
}

template <Message T>
msg::Gid Publisher<T>::gid() const { return detail::gid_of(core_->entity); }
template <Message T>
msg::Gid Subscriber<T>::gid() const { return detail::gid_of(core_->entity); }

template <Message T>
const std::string& Subscriber<T>::topic() const noexcept { return core_->topic_name; }
template <Message T>
const Qos& Subscriber<T>::qos() const noexcept { return core_->qos; }

#define TRIPODAL_DDS_INSTANTIATE(Type)      \
  template class Publisher<msg::Type>; \
  template class Subscriber<msg::Type>
TRIPODAL_DDS_INSTANTIATE(String);
TRIPODAL_DDS_INSTANTIATE(Twist);
TRIPODAL_DDS_INSTANTIATE(PoseWithCovarianceStamped);
TRIPODAL_DDS_INSTANTIATE(Odometry);
TRIPODAL_DDS_INSTANTIATE(OccupancyGrid);
TRIPODAL_DDS_INSTANTIATE(LaserScan);
TRIPODAL_DDS_INSTANTIATE(JointState);
TRIPODAL_DDS_INSTANTIATE(Clock);
TRIPODAL_DDS_INSTANTIATE(TFMessage);
TRIPODAL_DDS_INSTANTIATE(Imu);
TRIPODAL_DDS_INSTANTIATE(ParticipantEntitiesInfo);
TRIPODAL_DDS_INSTANTIATE(Event);
TRIPODAL_DDS_INSTANTIATE(TaskCommand);
TRIPODAL_DDS_INSTANTIATE(SimStep);
TRIPODAL_DDS_INSTANTIATE(SimState);
#undef TRIPODAL_DDS_INSTANTIATE

}  // namespace tripodal::dds
