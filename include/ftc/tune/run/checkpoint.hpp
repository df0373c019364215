#pragma once
// The checkpoint of `ftctune run` (checkpoint.json in the run directory): what an interrupted run
// needs to continue from its last finished iteration and end with the gains file, history and
// trials an uninterrupted run writes. It is bound to its job (the canonical SHA-256) and seed, and
// carries a digest of its content, so a file from another job or a damaged one is refused, never
// silently taken for a fresh start.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace ftc::tune {

inline constexpr const char* kCheckpointSchema = "ftctune.checkpoint/1";
inline constexpr const char* kCheckpointFile = "checkpoint.json";

// The file's text: schema, job_sha256, seed, iteration, state (a run_checkpoint()) and
// state_sha256 (of the state's compact JSON).
std::string checkpoint_text(const std::string& job_sha256, std::uint64_t seed, int iteration,
                            const nlohmann::json& state);

struct Checkpoint {
  int iteration = 0;     // the last iteration it holds
  nlohmann::json state;  // for RunOptions::resume
};

// Reads a checkpoint written for this job and seed. Throws InputError naming the file when it is
// not a checkpoint, is damaged (unreadable JSON, a digest that does not match its state), or was
// written by a run of another job or seed.
Checkpoint read_checkpoint(const std::filesystem::path& file, const std::string& job_sha256,
                           std::uint64_t seed);

}  // namespace ftc::tune
