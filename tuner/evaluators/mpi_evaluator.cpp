// MPI batch evaluation: rank 0 hands out packs of tasks, every rank simulates them.
//
// Protocol (all on MPI_COMM_WORLD, point to point with rank 0):
//   0 -> w  kHello     threads wanted          w -> 0  kHello    threads, host name
//   0 -> w  kSet       the simulation set: plant spec, scenarios (JSON), their options; when
//                      the batch's set is not the one the workers hold
//   0 -> w  kBatch     candidates, record_every; the worker answers with a kRequest
//   w -> 0  kRequest   capacity                0 -> w  kPack     tasks | kDone (batch over)
//   w -> 0  kResult    capacity + results of the pack (also asks for the next pack)
//   w -> 0  kHeartbeat every second while it simulates a pack
//   0 -> w  kStop      the session ends
// Messages from one rank arrive in the order sent, so a worker's heartbeats always come before
// the result of its pack and nothing of one batch reaches the next.
//
// Nobody blocks in MPI waiting for a message: Open MPI's blocking receive spins a core at 100 %,
// which would take a core from rank 0's simulations and keep idle workers busy. Waits probe and
// sleep instead, briefly while work is moving and up to a millisecond when idle.
#include "ftc/tune/evaluators/mpi_evaluator.hpp"

#include <mpi.h>
#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <thread>
#include <type_traits>

#include "ftc/runtime/scenario_json.hpp"
#include "ftc/sim/metrics_record.hpp"
#include "ftc/sim/plant_plugin.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"

namespace ftc::tune::mpi {
namespace {

using clock = std::chrono::steady_clock;
using nlohmann::json;

enum Tag : int {
  kHello = 1,
  kSet,
  kBatch,
  kPack,
  kDone,
  kRequest,
  kResult,
  kHeartbeat,
  kStop,
};

// The whole MPI job ends: a lost rank must not leave the others waiting for it.
[[noreturn]] void abort_job(const std::string& message) {
  std::fprintf(stderr, "ftctune: error: %s\n", message.c_str());
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, 1);
  std::abort();  // MPI_Abort does not return
}

// Bytes of a message. Every rank runs the same binary on the same kind of machine (an MPI job's
// premise), so values travel in their memory form.
class Writer {
 public:
  template <class T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const char* p = reinterpret_cast<const char*>(&v);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  template <class T>
  void put_vector(const std::vector<T>& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    put<std::uint64_t>(v.size());
    const char* p = reinterpret_cast<const char*>(v.data());
    bytes_.insert(bytes_.end(), p, p + v.size() * sizeof(T));
  }
  void put_string(const std::string& s) {
    put<std::uint64_t>(s.size());
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  void put_metrics(const sim::Metrics& m) { sim::append_metrics_wire(bytes_, m); }
  const std::vector<char>& bytes() const { return bytes_; }

 private:
  std::vector<char> bytes_;
};

class Reader {
 public:
  explicit Reader(const std::vector<char>& bytes) : bytes_(bytes) {}
  template <class T>
  T get() {
    static_assert(std::is_trivially_copyable_v<T>);
    T v;
    std::memcpy(&v, take(sizeof(T)), sizeof(T));
    return v;
  }
  template <class T>
  std::vector<T> get_vector() {
    const auto n = get<std::uint64_t>();
    if (n > bytes_.size()) throw std::runtime_error("malformed MPI message");
    std::vector<T> v(n);
    if (n > 0) std::memcpy(v.data(), take(n * sizeof(T)), n * sizeof(T));
    return v;
  }
  sim::Metrics get_metrics() { return sim::read_metrics_wire(bytes_, pos_); }
  std::string get_string() {
    const auto n = get<std::uint64_t>();
    if (n > bytes_.size()) throw std::runtime_error("malformed MPI message");
    return std::string(take(n), n);
  }

 private:
  const char* take(std::size_t n) {
    if (n > bytes_.size() - pos_) throw std::runtime_error("malformed MPI message");
    const char* p = bytes_.data() + pos_;
    pos_ += n;
    return p;
  }
  const std::vector<char>& bytes_;
  std::size_t pos_ = 0;
};

// Metrics in the record's wire form (ftc/sim/metrics_record.hpp: produced from kMetricFields,
// which checks at compile time that it lists every member of the record).
void put_metrics(Writer& w, const sim::Metrics& m) { w.put_metrics(m); }

sim::Metrics get_metrics(Reader& r) { return r.get_metrics(); }

static_assert(std::is_trivially_copyable_v<sim::ControllerConfig>);
static_assert(std::is_trivially_copyable_v<SimulationTask>);
static_assert(std::is_trivially_copyable_v<sim::Window>);

// The mirror of SimulationOptions, as for Metrics: a member added to it stops this compiling
// until set_message sends it.
struct OptionsMirror {
  sim::Window window;
  std::vector<sim::Window> extra_windows;
  std::int64_t record_every;
  sim::MetricSettings metrics;
};
static_assert(std::is_trivially_copyable_v<sim::MetricSettings>);
static_assert(sizeof(OptionsMirror) == sizeof(sim::SimulationOptions), "send every option");

void send(int to, int tag, const std::vector<char>& bytes) {
  MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD);
}
void send(int to, int tag, const Writer& w) { send(to, tag, w.bytes()); }
void send_empty(int to, int tag) { send(to, tag, std::vector<char>{}); }

// Rank 0's sends to workers. A message above MPI's eager limit waits until the receiver takes
// it, and a hung receiver never does: rank 0 sends without blocking, to every rank at once, and
// gives up on a rank that has not taken its message within the rank timeout. `host` names each
// rank's host once the ranks have said it (the greeting has not yet).
void send_to_ranks(const std::vector<int>& to, int tag, const std::vector<char>& bytes,
                   double timeout_s, const std::vector<std::string>* host = nullptr) {
  std::vector<MPI_Request> req(to.size());
  for (std::size_t i = 0; i < to.size(); ++i)
    MPI_Isend(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, to[i], tag, MPI_COMM_WORLD,
              &req[i]);
  const auto deadline = clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    int done = 0;
    MPI_Testall(static_cast<int>(req.size()), req.data(), &done, MPI_STATUSES_IGNORE);
    if (done) return;
    if (clock::now() > deadline)
      for (std::size_t i = 0; i < to.size(); ++i) {
        int one = 0;
        MPI_Test(&req[i], &one, MPI_STATUS_IGNORE);
        if (!one)
          abort_job("rank " + std::to_string(to[i]) +
                    (host ? " (on " + (*host)[static_cast<std::size_t>(to[i])] + ")" : "") +
                    " has not answered for " + std::to_string(static_cast<int>(timeout_s)) +
                    " s (it did not take a message): it hung or was lost; stopping the run (no "
                    "gains file is written)");
      }
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
}

struct Message {
  int source = 0, tag = 0;
  std::vector<char> bytes;
};

std::optional<Message> try_receive(int source) {
  int flag = 0;
  MPI_Status st;
  MPI_Iprobe(source, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
  if (!flag) return std::nullopt;
  int n = 0;
  MPI_Get_count(&st, MPI_BYTE, &n);
  Message m;
  m.source = st.MPI_SOURCE;
  m.tag = st.MPI_TAG;
  m.bytes.resize(static_cast<std::size_t>(n));
  MPI_Recv(m.bytes.data(), n, MPI_BYTE, st.MPI_SOURCE, st.MPI_TAG, MPI_COMM_WORLD,
           MPI_STATUS_IGNORE);
  return m;
}

// Sleeps between probes: 20 µs at first, doubling up to `cap` while nothing comes, and to 20 ms
// once nothing has come for a second (a worker rank of an idle service). Inside a batch the cap
// is 200 µs: the last results of an iteration are waited for, and each sleep adds to its time.
class Backoff {
 public:
  explicit Backoff(std::chrono::microseconds cap = std::chrono::microseconds(1000)) : cap_(cap) {}
  void reset() {
    wait_ = std::chrono::microseconds(20);
    since_ = clock::now();
  }
  void pause() {
    std::this_thread::sleep_for(wait_);
    const bool idle = clock::now() - since_ > std::chrono::seconds(1);
    wait_ = std::min(wait_ * 2, idle ? std::chrono::microseconds(20000) : cap_);
  }

 private:
  std::chrono::microseconds cap_;
  std::chrono::microseconds wait_{20};
  clock::time_point since_ = clock::now();
};

constexpr std::chrono::microseconds kInBatch{200};

Message receive_from(int source, std::chrono::microseconds cap = std::chrono::microseconds(1000)) {
  Backoff b(cap);
  for (;;) {
    if (std::optional<Message> m = try_receive(source)) return std::move(*m);
    b.pause();
  }
}

std::string host_name() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0) return "unknown";
  return buf;
}

// For a plugin plant, the digest of the library this rank loaded ("" for a shipped plant): every
// rank must run the same plant, and a plugin of the same name elsewhere on a rank's search path
// may be another build.
std::string plugin_digest(const std::string& model) {
  if (model.rfind(sim::kPluginPrefix, 0) != 0) return "";
  return sim::find_plant_plugin(model).digest;
}

// A simulation set as a worker rebuilds it: the plant's spec (with its plugin's digest), every
// scenario as JSON (resolved,
// so a slice, an ensemble member or a perturbed copy travels as it is) and each one's options.
std::vector<char> set_message(const SimulationSet& set) {
  Writer w;
  w.put_string(set.plant_spec().model);
  w.put_vector(set.plant_spec().values);
  w.put_string(plugin_digest(set.plant_spec().model));
  json scenarios = json::array();
  for (std::size_t i = 0; i < set.size(); ++i) {
    // A sensed scenario travels with its resolved noise stream as its own `seed` and `stream`,
    // which the worker's reading resolves back (the job's list index is not in its JSON).
    sim::Scenario s = set.scenario(i);
    if (s.sensors) {
      s.sensors->seed = s.sensors->stream_seed;
      s.sensors->stream = s.sensors->stream_index;
    }
    scenarios.push_back(runtime::to_json(s));
  }
  w.put_string(scenarios.dump());
  for (std::size_t i = 0; i < set.size(); ++i) {
    const sim::SimulationOptions& o = set.options(i);
    w.put(o.window);
    w.put_vector(o.extra_windows);
    w.put(o.record_every);
    w.put(o.metrics);
  }
  return w.bytes();
}

SimulationSet set_from_message(const std::vector<char>& bytes) {
  Reader r(bytes);
  sim::PlantSpec plant;
  plant.model = r.get_string();
  plant.values = r.get_vector<double>();
  const std::string digest = r.get_string();
  if (const std::string mine = plugin_digest(plant.model); mine != digest)
    throw std::runtime_error(
        plant.model + " here is not rank 0's: this rank loaded " +
        sim::find_plant_plugin(plant.model).file.string() + " (digest " + mine +
        "), rank 0's has digest " + digest +
        "; give every rank the same library (--plant-path or FTCTUNE_PLANT_PATH)");
  const json list = json::parse(r.get_string());
  std::vector<sim::Scenario> scenarios;
  std::vector<sim::SimulationOptions> options(list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    scenarios.push_back(runtime::scenario_from_json(list[i], "scenario from rank 0"));
    options[i].window = r.get<sim::Window>();
    options[i].extra_windows = r.get_vector<sim::Window>();
    options[i].record_every = r.get<std::int64_t>();
    options[i].metrics = r.get<sim::MetricSettings>();
  }
  return SimulationSet(std::move(plant), std::move(scenarios), std::move(options));
}

std::vector<char> results_message(int capacity, std::span<const TaskResult> results) {
  Writer w;
  w.put<std::int32_t>(capacity);
  w.put<std::uint64_t>(results.size());
  for (const TaskResult& r : results) {
    put_metrics(w, r.metrics);
    w.put_string(r.error);
  }
  return w.bytes();
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Session and the worker ranks

Session::Session(int& argc, char**& argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_SERIALIZED, &provided);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  if (provided < MPI_THREAD_SERIALIZED)
    abort_job(
        "this MPI library does not allow MPI calls from more than one thread "
        "(MPI_THREAD_SERIALIZED)");
}

Session::~Session() {
  if (rank_ == 0)
    for (int w = 1; w < size_; ++w) send_empty(w, kStop);
  MPI_Finalize();
}

int Session::serve() {
  std::unique_ptr<TbbEvaluator> evaluator;
  std::optional<SimulationSet> set;
  for (;;) {
    Message m = receive_from(0);
    try {
      switch (m.tag) {
        case kStop:
          return 0;
        case kHello: {
          Reader r(m.bytes);
          evaluator = std::make_unique<TbbEvaluator>(r.get<std::int32_t>());
          Writer w;
          w.put<std::int32_t>(evaluator->concurrency());
          w.put_string(host_name());
          send(0, kHello, w);
          break;
        }
        case kSet:
          set.emplace(set_from_message(m.bytes));
          spdlog::debug("rank {}: simulation set with {} scenarios", rank_, set->size());
          break;
        case kBatch: {
          if (!evaluator || !set) abort_job("rank 0 sent a batch before its simulation set");
          Reader r(m.bytes);
          const auto record_every = r.get<std::int64_t>();
          const std::vector<sim::ControllerConfig> candidates =
              r.get_vector<sim::ControllerConfig>();
          // Enough tasks to fill the SIMD lanes of every thread.
          const int capacity = evaluator->concurrency() * std::max(1, set->plant().pack_width());
          Writer req;
          req.put<std::int32_t>(capacity);
          send(0, kRequest, req);
          for (;;) {
            Message p = receive_from(0, kInBatch);
            if (p.tag == kDone) break;
            if (p.tag != kPack) abort_job("unexpected message from rank 0 inside a batch");
            Reader pr(p.bytes);
            const std::vector<SimulationTask> tasks = pr.get_vector<SimulationTask>();
            // The pack runs on the rank's threads while this thread tells rank 0 it is alive.
            std::vector<TaskResult> results;
            std::mutex mu;
            std::condition_variable cv;
            bool done = false;
            std::string failed;  // what escaped the pack (out of memory): ends the job below
            std::thread compute([&] {
              std::vector<TaskResult> out;
              std::string error;
              try {
                out = evaluator->run({*set, candidates, tasks, record_every});
              } catch (const std::exception& e) {
                error = e.what();
              }
              std::lock_guard lock(mu);
              results = std::move(out);
              failed = std::move(error);
              done = true;
              cv.notify_one();
            });
            {
              std::unique_lock lock(mu);
              while (!cv.wait_for(lock, std::chrono::seconds(1), [&] { return done; })) {
                lock.unlock();
                send_empty(0, kHeartbeat);
                lock.lock();
              }
            }
            compute.join();
            if (!failed.empty()) throw std::runtime_error(failed);
            send(0, kResult, results_message(capacity, results));
          }
          break;
        }
        default:
          abort_job("unexpected message from rank 0 (tag " + std::to_string(m.tag) + ")");
      }
    } catch (const std::exception& e) {
      abort_job("rank " + std::to_string(rank_) + ": " + e.what());
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Rank 0

struct MpiEvaluator::Impl {
  MpiOptions options;
  int size = 1;
  tbb::task_arena arena;
  std::vector<int> threads;       // per rank
  std::vector<std::string> host;  // per rank
  std::uint64_t set_sent = 0;     // identity of the simulation set the workers hold

  Impl(const Session& s, MpiOptions o)
      : options(o),
        size(s.size()),
        arena(o.threads > 0 ? o.threads : tbb::this_task_arena::max_concurrency()) {}
};

MpiEvaluator::MpiEvaluator(Session& session, MpiOptions options)
    : impl_(std::make_unique<Impl>(session, options)) {
  Impl& s = *impl_;
  if (session.rank() != 0) throw std::logic_error("MpiEvaluator belongs to rank 0");
  s.threads.assign(static_cast<std::size_t>(s.size), 0);
  s.host.assign(static_cast<std::size_t>(s.size), host_name());
  s.threads[0] = s.arena.max_concurrency();
  Writer hello;
  hello.put<std::int32_t>(options.threads);
  std::vector<int> all;
  for (int w = 1; w < s.size; ++w) all.push_back(w);
  send_to_ranks(all, kHello, hello.bytes(), options.rank_timeout);
  const auto deadline = clock::now() + std::chrono::duration<double>(options.rank_timeout);
  Backoff b;
  for (int answered = 1; answered < s.size;) {
    if (std::optional<Message> m = try_receive(MPI_ANY_SOURCE)) {
      if (m->tag != kHello) abort_job("unexpected message while greeting the ranks");
      Reader r(m->bytes);
      s.threads[static_cast<std::size_t>(m->source)] = r.get<std::int32_t>();
      s.host[static_cast<std::size_t>(m->source)] = r.get_string();
      ++answered;
      b.reset();
      continue;
    }
    if (clock::now() > deadline)
      for (int w = 1; w < s.size; ++w)
        if (s.threads[static_cast<std::size_t>(w)] == 0)
          abort_job("rank " + std::to_string(w) + " did not answer within " +
                    std::to_string(static_cast<int>(options.rank_timeout)) +
                    " s of the start: it hung or was lost; stopping");
    b.pause();
  }
}

MpiEvaluator::~MpiEvaluator() = default;

int MpiEvaluator::concurrency() const {
  int n = 0;
  for (int t : impl_->threads) n += t;
  return n;
}

std::vector<int> MpiEvaluator::threads_per_rank() const { return impl_->threads; }

std::vector<TaskResult> MpiEvaluator::run(const SimulationBatch& batch) {
  Impl& s = *impl_;
  const std::size_t n = batch.tasks.size();
  std::vector<TaskResult> results(n);
  if (n == 0) return results;

  // Tasks that record a trajectory stay here (a trajectory is large and only the comparison
  // records them); the others are shared out.
  std::vector<std::size_t> shared, local;
  for (std::size_t k = 0; k < n; ++k) (batch.tasks[k].record ? local : shared).push_back(k);
  std::atomic<std::size_t> next_shared{0}, next_local{0};
  // Takes up to `want` shared tasks: [first, first + count).
  const auto take = [&](std::size_t want) -> std::pair<std::size_t, std::size_t> {
    std::size_t first = next_shared.load();
    std::size_t count = 0;
    do {
      count = std::min(want, shared.size() - std::min(first, shared.size()));
    } while (count > 0 && !next_shared.compare_exchange_weak(first, first + count));
    return {first, count};
  };

  const int workers = s.size - 1;
  const auto t0 = clock::now();
  std::size_t bytes_out = 0, bytes_in = 0, packs = 0;
  std::vector<int> ranks;
  for (int w = 1; w <= workers; ++w) ranks.push_back(w);
  if (workers > 0) {
    if (batch.set.identity() != s.set_sent) {
      const std::vector<char> bytes = set_message(batch.set);
      send_to_ranks(ranks, kSet, bytes, s.options.rank_timeout, &s.host);
      bytes_out += bytes.size() * static_cast<std::size_t>(workers);
      s.set_sent = batch.set.identity();
    }
    Writer b;
    b.put<std::int64_t>(batch.record_every);
    b.put_vector(
        std::vector<sim::ControllerConfig>(batch.candidates.begin(), batch.candidates.end()));
    send_to_ranks(ranks, kBatch, b.bytes(), s.options.rank_timeout, &s.host);
    bytes_out += b.bytes().size() * static_cast<std::size_t>(workers);
  }

  // Rank 0's own threads take its recorded tasks one at a time, then shared ones a pack at a time.
  const auto width = static_cast<std::size_t>(std::max(1, batch.set.plant().pack_width()));
  std::atomic<bool> local_done{false};
  std::string local_error;  // what escaped rank 0's own simulations (out of memory)
  std::thread compute([&] {
    try {
      s.arena.execute([&] {
        const std::size_t slots = static_cast<std::size_t>(s.arena.max_concurrency());
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, slots, 1),
                          [&](const tbb::blocked_range<std::size_t>&) {
                            for (std::size_t i; (i = next_local++) < local.size();)
                              results[local[i]] = run_task(batch, local[i]);
                            // Shared tasks a SIMD pack at a time.
                            for (;;) {
                              const auto [first, count] = take(width);
                              if (count == 0) break;
                              run_pack(batch,
                                       std::span<const std::size_t>(shared).subspan(first, count),
                                       results);
                            }
                          });
      });
    } catch (const std::exception& e) {
      local_error = e.what();
    }
    local_done = true;
  });

  // The dispatch loop: answer requests, place results, watch for silent ranks.
  struct Worker {
    bool active = true;  // in this batch and not yet told it is over
    std::optional<std::pair<std::size_t, std::size_t>> pack;  // [first, first + count)
    clock::time_point heard = clock::now();
  };
  std::vector<Worker> ws(static_cast<std::size_t>(s.size));
  const double total_threads = std::max(1, concurrency());
  const auto timeout = std::chrono::duration<double>(s.options.rank_timeout);
  Backoff backoff(kInBatch);
  // A malformed message ends the job (its compute thread cannot be left running otherwise).
  try {
    for (int active = workers; active > 0 || !local_done;) {
      if (local_done && !local_error.empty()) abort_job("rank 0: " + local_error);
      std::optional<Message> m = workers > 0 ? try_receive(MPI_ANY_SOURCE) : std::nullopt;
      if (!m) {
        const auto now = clock::now();
        for (int w = 1; w <= workers; ++w) {
          const Worker& wk = ws[static_cast<std::size_t>(w)];
          if (wk.active && now - wk.heard > timeout)
            abort_job("rank " + std::to_string(w) + " (on " + s.host[static_cast<std::size_t>(w)] +
                      ") has not answered for " +
                      std::to_string(static_cast<int>(s.options.rank_timeout)) +
                      " s while holding work: it hung or was lost; stopping the run (no gains file "
                      "is written)");
        }
        backoff.pause();
        continue;
      }
      backoff.reset();
      bytes_in += m->bytes.size();
      Worker& wk = ws[static_cast<std::size_t>(m->source)];
      wk.heard = clock::now();
      if (m->tag == kHeartbeat) continue;
      if (m->tag != kRequest && m->tag != kResult)
        abort_job("unexpected message from rank " + std::to_string(m->source));
      Reader r(m->bytes);
      const int capacity = std::max(1, r.get<std::int32_t>());
      if (m->tag == kResult) {
        if (!wk.pack) abort_job("rank " + std::to_string(m->source) + " sent results it owed none");
        const auto [first, count] = *wk.pack;
        if (r.get<std::uint64_t>() != count)
          abort_job("rank " + std::to_string(m->source) + " sent the wrong number of results");
        for (std::size_t i = 0; i < count; ++i) {
          TaskResult& t = results[shared[first + i]];
          t.metrics = get_metrics(r);
          t.error = r.get_string();
        }
        wk.pack.reset();
      }
      // Guided self-scheduling: a share of what is left in proportion to the rank's threads, at
      // least one task per thread, so the packs shrink as the batch ends.
      const std::size_t left = shared.size() - std::min(next_shared.load(), shared.size());
      // (A rank's capacity is its threads times its SIMD pack width, taken to be rank 0's.)
      const auto want = static_cast<std::size_t>(std::max<double>(
          capacity, std::ceil(static_cast<double>(left) * capacity /
                              (2.0 * total_threads * static_cast<double>(width)))));
      const auto [first, count] = take(want);
      if (count == 0) {
        send_to_ranks({m->source}, kDone, {}, s.options.rank_timeout, &s.host);
        wk.active = false;
        --active;
        continue;
      }
      std::vector<SimulationTask> tasks(count);
      for (std::size_t i = 0; i < count; ++i) tasks[i] = batch.tasks[shared[first + i]];
      Writer p;
      p.put_vector(tasks);
      send_to_ranks({m->source}, kPack, p.bytes(), s.options.rank_timeout, &s.host);
      bytes_out += p.bytes().size();
      ++packs;
      wk.pack = std::make_pair(first, count);
    }
  } catch (const std::exception& e) {
    abort_job(std::string("rank 0: ").append(e.what()));
  }
  compute.join();
  spdlog::debug(
      "mpi batch: {} tasks, {} packs to {} worker ranks, {:.1f} kB out, {:.1f} kB in, "
      "{:.1f} ms",
      n, packs, workers, bytes_out / 1e3, bytes_in / 1e3,
      std::chrono::duration<double, std::milli>(clock::now() - t0).count());
  return results;
}

}  // namespace ftc::tune::mpi
