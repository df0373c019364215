#include "noise_tables.hpp"

#include <bit>
#include <list>
#include <mutex>

namespace ftc::sim::detail {

namespace {

// What a table depends on, by bits: the stream, the noise levels, the bias, the shape.
struct Key {
  std::vector<std::uint64_t> bits;
  bool operator==(const Key&) const = default;
};

Key key_of(const SensorModel& m, int axes, double Ts, std::int64_t samples) {
  const auto b = [](double v) { return std::bit_cast<std::uint64_t>(v); };
  Key k{{m.stream_seed, m.stream_index, b(m.angle.noise), b(m.rate.noise), b(m.rate.bias_walk),
         static_cast<std::uint64_t>(axes), b(Ts), static_cast<std::uint64_t>(samples)}};
  for (int i = 0; i < axes; ++i) k.bits.push_back(b(m.rate.bias_of(i)));
  return k;
}

struct Entry {
  Key key;
  std::shared_ptr<const NoiseTable> table;
};

std::mutex mutex;
std::list<Entry> entries;  // most recently used first
std::size_t held_bytes = 0;

std::size_t bytes_of(const NoiseTable& t) { return t.size() * sizeof(double); }

}  // namespace

std::shared_ptr<const NoiseTable> noise_table(const SensorModel& model, int axes,
                                              double sample_time, std::int64_t samples) {
  const std::size_t bytes =
      static_cast<std::size_t>(samples) * 3 * static_cast<std::size_t>(axes) * sizeof(double);
  if (samples <= 0 || bytes > kNoiseCacheBytes / 4) return nullptr;
  const Key key = key_of(model, axes, sample_time, samples);
  {
    const std::lock_guard lock(mutex);
    for (auto it = entries.begin(); it != entries.end(); ++it)
      if (it->key == key) {
        entries.splice(entries.begin(), entries, it);
        return it->table;
      }
  }
  // Drawn outside the lock: two threads may draw the same table at once, and keep the same bits.
  auto table = std::make_shared<NoiseTable>(bytes / sizeof(double));
  SensorNoise noise(model, axes, sample_time);
  for (std::int64_t k = 0; k < samples; ++k) {
    double* row = table->data() + k * 3 * axes;
    noise.next(row, row + axes, row + 2 * axes);
  }
  const std::lock_guard lock(mutex);
  for (const Entry& e : entries)
    if (e.key == key) return e.table;
  entries.push_front({key, table});
  held_bytes += bytes;
  while (held_bytes > kNoiseCacheBytes && entries.size() > 1) {
    held_bytes -= bytes_of(*entries.back().table);
    entries.pop_back();
  }
  return table;
}

}  // namespace ftc::sim::detail
