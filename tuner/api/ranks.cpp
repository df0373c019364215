// MPI ranks of a process (`mpirun -np N ftctune COMMAND ...`): rank 0 runs the command, every
// other rank simulates for it until it finishes; and the evaluator the run API uses. A process not
// started by an MPI launcher never touches MPI (initialising it costs time and, outside a launcher,
// may fail).
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "ftc/sim/input_error.hpp"
#include "ftc/tune/evaluators/tbb_evaluator.hpp"
#include "ftc/tune/api/api.hpp"
#if FTC_WITH_MPI
#include "ftc/tune/evaluators/mpi_evaluator.hpp"
#endif

namespace ftc::tune {
namespace {

// The size of the MPI job this process belongs to, from the launcher's environment (Open MPI's
// mpirun, or srun and other PMIx/PMI launchers); 0 when it was not started by one.
int launched_size() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_SIZE", "PMI_SIZE"})
    if (const char* s = std::getenv(v)) return std::atoi(s);
  return 0;
}

#if !FTC_WITH_MPI
bool launched_as_rank_zero() {
  for (const char* v : {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"})
    if (const char* s = std::getenv(v)) return std::atoi(s) == 0;
  return true;
}
#endif

#if FTC_WITH_MPI
std::unique_ptr<mpi::Session> g_session;
#endif

double rank_timeout() {
  const char* s = std::getenv("FTCTUNE_RANK_TIMEOUT");
  if (!s || !*s) return 10.0;
  char* end = nullptr;
  const double t = std::strtod(s, &end);
  if (*end != '\0' || !(t >= 1.0 && t <= 86400.0))
    throw InputError(
        "FTCTUNE_RANK_TIMEOUT", "",
        std::string("must be a number of seconds in [1, 86400] (got \"").append(s).append("\")"));
  return t;
}

}  // namespace

Ranks::Ranks(int& argc, char**& argv) {
  if (launched_size() <= 1) return;
#if FTC_WITH_MPI
  g_session = std::make_unique<mpi::Session>(argc, argv);
  rank_ = g_session->rank();
  size_ = g_session->size();
#else
  (void)argc;
  (void)argv;
  failed_ = true;
  if (launched_as_rank_zero())
    std::fprintf(stderr,
                 "ftctune: error: started by mpirun as one of %d ranks, but this ftctune was built "
                 "without MPI: install libopenmpi-dev and openmpi-bin (tools/bootstrap does) and "
                 "rebuild, or run it without mpirun\n",
                 launched_size());
#endif
}

Ranks::~Ranks() {
#if FTC_WITH_MPI
  g_session.reset();  // rank 0 releases the other ranks
#endif
}

int Ranks::serve() {
#if FTC_WITH_MPI
  // mpirun passes SIGTERM and SIGINT on to every rank; a worker ends when rank 0 says so (after
  // rank 0 has shut down in order), or is killed by mpirun when rank 0 is gone.
  std::signal(SIGTERM, SIG_IGN);
  std::signal(SIGINT, SIG_IGN);
  return g_session->serve();
#else
  return 2;
#endif
}

int mpi_ranks() {
#if FTC_WITH_MPI
  return g_session ? g_session->size() : 1;
#else
  return 1;
#endif
}

std::unique_ptr<BatchEvaluator> make_evaluator(int threads) {
#if FTC_WITH_MPI
  if (g_session && g_session->size() > 1)
    return std::make_unique<mpi::MpiEvaluator>(
        *g_session, mpi::MpiOptions{.threads = threads, .rank_timeout = rank_timeout()});
#endif
  return std::make_unique<TbbEvaluator>(threads);
}

}  // namespace ftc::tune
