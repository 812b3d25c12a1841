// MPI runtime and communicator (mpi.hpp).
#include "renderer/cluster/mpi.hpp"

#include <cstdlib>
#include <iostream>

#include <mpi.h>

#include "io/error.hpp"

namespace iso::cluster {

bool launched_by_mpirun() {
    // OpenMPI's mpirun sets OMPI_COMM_WORLD_SIZE; PMIx and PMI launchers
    // (srun, MPICH's hydra) set PMIX_RANK / PMI_RANK.
    for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"})
        if (std::getenv(name)) return true;
    return false;
}

namespace {
void check(int rc, const char* what) {
    if (rc == MPI_SUCCESS) return;
    char text[MPI_MAX_ERROR_STRING];
    int len = 0;
    MPI_Error_string(rc, text, &len);
    // A failed MPI call leaves the communicator in an unknown state: agreeing
    // through it could hang, so this is the last-resort path.
    Runtime::abort_job(std::string(what) + " failed: " + std::string(text, std::size_t(len)));
}
int world_rank() {
    int initialized = 0, rank = 0;
    MPI_Initialized(&initialized);
    if (initialized) MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    return rank;
}
} // namespace

Runtime::Runtime(int* argc, char*** argv) {
    int provided = 0;
    if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS)
        throw Error("MPI", "MPI_Init_thread failed");
    // Errors come back as codes (check() turns them into an abort with a message).
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
}

Runtime::~Runtime() {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Finalize();
}

void Runtime::abort_job(const std::string& message, int code) {
    std::cerr << "isoscope: error: rank " << world_rank() << ": " << message << " (aborting the MPI job)" << std::endl;
    MPI_Abort(MPI_COMM_WORLD, code);
    std::_Exit(code);
}

Comm::Comm() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

void Comm::agree(const std::string& error) const {
    // One small allreduce in the common case (every rank fine); the messages
    // travel only when some rank failed.
    int failed = error.empty() ? 0 : 1, any = 0;
    check(MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD), "MPI_Allreduce (agreement)");
    if (any == 0) return;
    const auto messages = [&] {
        int len = int(error.size());
        std::vector<int> lens(static_cast<std::size_t>(size_)), offs(std::size_t(size_) + 1, 0);
        check(MPI_Allgather(&len, 1, MPI_INT, lens.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Allgather (agreement)");
        for (int r = 0; r < size_; ++r) offs[r + 1] = offs[r] + lens[r];
        std::string all(std::size_t(offs[size_]), '\0');
        check(
            MPI_Allgatherv(error.data(), len, MPI_CHAR, all.data(), lens.data(), offs.data(), MPI_CHAR, MPI_COMM_WORLD),
            "MPI_Allgatherv (agreement)");
        std::vector<std::string> out;
        for (int r = 0; r < size_; ++r) out.push_back(all.substr(std::size_t(offs[r]), std::size_t(lens[r])));
        return out;
    }();
    int first = -1;
    for (int r = 0; r < size_; ++r)
        if (!messages[r].empty() && first < 0) first = r;
    std::string reason = messages[first];
    if (any > 1) reason += " (and " + std::to_string(any - 1) + " other rank" + (any > 2 ? "s" : "") + " failed)";
    throw AgreedError("rank " + std::to_string(first), reason);
}

namespace {
template <class T> std::vector<T> allreduce(std::span<const T> x, MPI_Datatype type, MPI_Op op) {
    std::vector<T> out(x.size());
    check(MPI_Allreduce(x.data(), out.data(), int(x.size()), type, op, MPI_COMM_WORLD), "MPI_Allreduce");
    return out;
}
} // namespace

std::vector<double> Comm::allreduce_sum(std::span<const double> x) const { return allreduce(x, MPI_DOUBLE, MPI_SUM); }
std::vector<double> Comm::allreduce_min(std::span<const double> x) const { return allreduce(x, MPI_DOUBLE, MPI_MIN); }
std::vector<double> Comm::allreduce_max(std::span<const double> x) const { return allreduce(x, MPI_DOUBLE, MPI_MAX); }
std::vector<std::uint64_t> Comm::allreduce_sum(std::span<const std::uint64_t> x) const {
    return allreduce(x, MPI_UINT64_T, MPI_SUM);
}

std::vector<std::uint8_t> Comm::allreduce_bor(std::span<const std::uint8_t> x) const {
    return allreduce(x, MPI_UINT8_T, MPI_BOR);
}

std::vector<double> Comm::allgatherv(std::span<const double> mine) const {
    // Counts are ints in MPI-3: 2^31 doubles per rank (16 GiB) is far beyond a
    // chunk index (2048^3 at 32 cells per chunk: 262144 chunks).
    const int n = int(mine.size());
    std::vector<int> counts(static_cast<std::size_t>(size_)), offs(std::size_t(size_) + 1, 0);
    check(MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Allgather");
    for (int r = 0; r < size_; ++r) offs[r + 1] = offs[r] + counts[r];
    std::vector<double> out(static_cast<std::size_t>(offs[size_]));
    check(
        MPI_Allgatherv(mine.data(), n, MPI_DOUBLE, out.data(), counts.data(), offs.data(), MPI_DOUBLE, MPI_COMM_WORLD),
        "MPI_Allgatherv");
    return out;
}

std::vector<std::string> Comm::gather(const std::string& mine, int root) const {
    // MPI-3 counts are ints; agreed, so that every rank stops together.
    agree(mine.size() > std::size_t(1) << 30
              ? "gathering to rank " + std::to_string(root) + ": more than 1 GiB from one rank"
              : std::string());
    const int n = int(mine.size());
    std::vector<int> counts(static_cast<std::size_t>(size_)), offs(std::size_t(size_) + 1, 0);
    check(MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, root, MPI_COMM_WORLD), "MPI_Gather");
    std::string all;
    if (rank_ == root) {
        for (int r = 0; r < size_; ++r) {
            // Displacements are ints too: the sum must fit.
            if (std::int64_t(offs[r]) + counts[r] > std::int64_t(0x7fffffff))
                Runtime::abort_job("gathering to rank " + std::to_string(root) + ": more than 2 GiB in all");
            offs[r + 1] = offs[r] + counts[r];
        }
        all.resize(std::size_t(offs[size_]));
    }
    check(MPI_Gatherv(mine.data(), n, MPI_CHAR, all.data(), counts.data(), offs.data(), MPI_CHAR, root, MPI_COMM_WORLD),
          "MPI_Gatherv");
    std::vector<std::string> out;
    if (rank_ == root)
        for (int r = 0; r < size_; ++r) out.push_back(all.substr(std::size_t(offs[r]), std::size_t(counts[r])));
    return out;
}

std::string Comm::broadcast(const std::string& bytes, int root) const {
    std::uint64_t n = bytes.size();
    check(MPI_Bcast(&n, 1, MPI_UINT64_T, root, MPI_COMM_WORLD), "MPI_Bcast");
    std::string out = rank_ == root ? bytes : std::string(n, '\0');
    check(MPI_Bcast(out.data(), int(n), MPI_CHAR, root, MPI_COMM_WORLD), "MPI_Bcast");
    return out;
}

void Comm::barrier() const { check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier"); }

} // namespace iso::cluster
