#pragma once
// Batch evaluation on every rank of an MPI job (`mpirun -np N ftctune run JOB`). Rank 0 runs the
// command and its optimiser; every rank, rank 0 included, simulates on its own threads. The
// batch's simulation set (the plant's spec, the scenarios with their options) goes to each rank
// once; per batch only the candidates go out, and per pack of tasks only their metrics come
// back. Packs are handed out on request, smaller towards the end of a batch, so a rank whose
// simulations diverge early simply asks for more. Results are placed by task index: the answer is
// the same bits for any number of ranks and threads.
//
// A worker rank that stops answering (hung, stopped, its node gone) for `rank_timeout` seconds
// while it holds work ends the whole MPI job with exit status 1 and a message naming the rank;
// one that dies is noticed by mpirun itself, which ends the job and names it.
//
// Trajectories are never sent: tasks that record one run on rank 0.
//
// Built only when Open MPI (libopenmpi-dev) is found; no MPI type appears here.
#include <memory>
#include <string>
#include <vector>

#include "ftc/tune/evaluators/batch_evaluator.hpp"

namespace ftc::tune::mpi {

// MPI from MPI_Init to MPI_Finalize: one per process, made after the command line is parsed.
class Session {
 public:
  // Asks for MPI_THREAD_SERIALIZED: the service calls MPI from its job thread, one call at a time.
  Session(int& argc, char**& argv);
  // Rank 0 tells the other ranks to finish; every rank finalizes MPI.
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  // A worker rank's life: simulate what rank 0 hands out until it ends the session. Returns the
  // process's exit code.
  int serve();

 private:
  int rank_ = 0, size_ = 1;
};

struct MpiOptions {
  int threads = 0;             // TBB threads on each rank; <= 0: every core of that rank's machine
  double rank_timeout = 10.0;  // s a rank holding work may stay silent (it reports every second)
};

// Rank 0's evaluator. Not for concurrent use: one batch at a time (MPI is serialized).
class MpiEvaluator final : public BatchEvaluator {
 public:
  // Greets every worker rank, which sets up its threads and reports them.
  MpiEvaluator(Session& session, MpiOptions options);
  ~MpiEvaluator() override;

  std::vector<TaskResult> run(const SimulationBatch& batch) override;
  int concurrency() const override;  // threads over all ranks
  std::vector<int> threads_per_rank() const override;
  std::string name() const override { return "mpi"; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ftc::tune::mpi
