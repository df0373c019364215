#include "ftc/tune/run/checkpoint.hpp"

#include <optional>

#include "ftc/sim/input_error.hpp"
#include "ftc/tune/io/files.hpp"
#include "ftc/tune/io/sha256.hpp"

namespace ftc::tune {

using nlohmann::json;

std::string checkpoint_text(const std::string& job_sha256, std::uint64_t seed, int iteration,
                            const json& state) {
  return json{{"schema", kCheckpointSchema},
              {"job_sha256", job_sha256},
              {"seed", seed},
              {"iteration", iteration},
              {"state", state},
              {"state_sha256", sha256_hex(state.dump())}}
             .dump() +
         "\n";
}

Checkpoint read_checkpoint(const std::filesystem::path& file, const std::string& job_sha256,
                           std::uint64_t seed) {
  const std::string source = file.string();
  const std::optional<std::string> text = read_file(file, json_io::kMaxCheckpointBytes);
  if (!text) throw InputError(source, "", "cannot read the checkpoint");
  const auto damaged = [&](const std::string& why) {
    return InputError(source, "",
                      "the checkpoint is damaged (" + why +
                          "); remove it and run without --resume to start over");
  };
  json j;
  try {
    j = json::parse(*text);
  } catch (const json::exception&) {
    throw damaged("not valid JSON");
  }
  if (!j.is_object() || j.value("schema", json()) != kCheckpointSchema)
    throw InputError(source, "/schema",
                     std::string("is not an ftctune checkpoint (expected schema \"") +
                         kCheckpointSchema + "\")");
  const auto field = [&](const char* key) -> const json& {
    if (!j.contains(key)) throw damaged(std::string("no \"").append(key).append("\""));
    return j[key];
  };
  const json& digest = field("state_sha256");
  const json& state = field("state");
  if (!digest.is_string() || sha256_hex(state.dump()) != digest.get<std::string>())
    throw damaged("its state does not match its digest");
  const json& sha = field("job_sha256");
  if (!sha.is_string() || sha.get<std::string>() != job_sha256)
    throw InputError(source, "/job_sha256",
                     "was written by a run of another job (job SHA-256 " +
                         (sha.is_string() ? sha.get<std::string>().substr(0, 12) : "?") +
                         "…, this job's is " + job_sha256.substr(0, 12) +
                         "…); resume with the job it was written for, or remove it");
  const json& s = field("seed");
  if (!s.is_number_unsigned() || s.get<std::uint64_t>() != seed)
    throw InputError(source, "/seed",
                     "was written by a run with seed " + s.dump() + ", not " +
                         std::to_string(seed) + "; resume with --seed " + s.dump() +
                         ", or remove it");
  const json& it = field("iteration");
  if (!it.is_number_integer()) throw damaged("\"iteration\" is not an integer");
  return {it.get<int>(), state};
}

}  // namespace ftc::tune
