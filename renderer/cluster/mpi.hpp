// The MPI runtime of a distributed job (docs/cluster.md): initialised only
// when the process was started by mpirun (a plain `isoscope` never calls
// MPI), and a small communicator with the few collectives the distributed
// extraction needs.
//
// Failure policy: every collective step first agrees on success. A rank that
// fails (a bad file region, a write error, any exception) passes its message
// to agree(); the others pass an empty one; agree() then throws the same
// iso::Error on every rank, naming the failing rank and its reason, so all
// ranks unwind, finalize and exit non-zero together instead of waiting
// forever in a collective that the failed rank never reaches. An exception
// that escapes outside an agreement point (a bug) ends the job with
// MPI_Abort after printing it (Runtime's last resort): a message and a
// non-zero exit rather than a hang.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "io/error.hpp"

namespace iso::cluster {

// The error every rank throws when the job agreed that some rank failed
// (Comm::agree): where() is "rank R", reason() that rank's message.
class AgreedError : public Error {
public:
    using Error::Error;
};

// Was this process started by an MPI launcher (OpenMPI's mpirun/mpiexec, or
// another PMI/PMIx launcher)? Reads the environment only.
bool launched_by_mpirun();

// Initialises MPI (MPI_THREAD_FUNNELED: TBB threads compute, only the main
// thread communicates) on construction and finalizes it on destruction.
// One per process.
class Runtime {
public:
    Runtime(int* argc, char*** argv);
    ~Runtime();
    Runtime(const Runtime&) = delete;
    Runtime& operator=(const Runtime&) = delete;
    // Prints `message` (with the rank) to stderr and aborts the whole job.
    [[noreturn]] static void abort_job(const std::string& message, int code = 1);
};

// MPI_COMM_WORLD with agreement on every step.
class Comm {
public:
    Comm();
    int rank() const { return rank_; }
    int size() const { return size_; }
    bool root() const { return rank_ == 0; }

    // Every rank calls it with its error message ("" when it succeeded). When
    // any message is non-empty, throws on every rank an AgreedError whose
    // `where` is "rank R" (the lowest failing rank) and whose reason is that
    // rank's message (plus how many other ranks failed).
    void agree(const std::string& error) const;

    // Collectives (all ranks call them, in the same order).
    std::vector<double> allreduce_sum(std::span<const double> x) const;
    std::vector<double> allreduce_min(std::span<const double> x) const;
    std::vector<double> allreduce_max(std::span<const double> x) const;
    std::vector<std::uint64_t> allreduce_sum(std::span<const std::uint64_t> x) const;
    std::vector<std::uint8_t> allreduce_bor(std::span<const std::uint8_t> x) const;
    // Every rank's `mine` concatenated in rank order, on every rank.
    std::vector<double> allgatherv(std::span<const double> mine) const;
    // Every rank's bytes, in rank order, on `root` (empty elsewhere).
    std::vector<std::string> gather(const std::string& mine, int root = 0) const;
    // `root`'s bytes on every rank.
    std::string broadcast(const std::string& bytes, int root = 0) const;
    void barrier() const;

private:
    int rank_ = 0, size_ = 1;
};

// Runs `step` and agrees on its success: the exception of any rank (its
// what()) becomes the agreed iso::Error on all of them.
template <class F> void agreed(const Comm& comm, F&& step) {
    std::string error;
    try {
        step();
    } catch (const AgreedError&) {
        throw; // a collective inside `step` already agreed: every rank has it
    } catch (const std::exception& e) {
        error = e.what();
        if (error.empty()) error = "unknown error";
    } catch (...) {
        error = "unknown exception";
    }
    comm.agree(error);
}

} // namespace iso::cluster
