// Running a library that is not hardened against malformed files in a child
// process, so that its crash, abort, hang or runaway allocation becomes an
// iso::Error naming the file instead of ending the program. Used for
// OpenVDB's reader (io/vdb.cpp: the fuzzer found heap overflows inside it)
// and GDCM's decoders of compressed DICOM pixel data (io/dicom_decode.cpp:
// Debian builds GDCM with its assertions on, and a fuzzed JPEG file aborts
// it).
//
// The child is this same program started again (/proc/self/exe with
// posix_spawn) and recognised before main() by its first argument (a flag of
// the reader's own; each reader has an ELF constructor that checks for it).
// Not a bare fork(): a forked copy of a process whose worker threads (TBB's,
// Qt's) held a lock at the fork can deadlock, which hung reads under parallel
// tests; an exec'd program starts clean. Re-executing ourselves needs no
// helper executable to install or find, and every program that links the
// reader (the CLI, the GUI, tests, fuzzers) has it.
//
// The child writes its product to kChildOutFd (a pipe) and "ok ..." or an
// error message to kChildStatusFd, and reads `input` on its standard input
// (a file in memory); its standard output goes to /dev/null (the CLI's JSON
// goes to ours) and its standard error (a library's chatter, an assertion's
// last words) to a file in memory whose text comes back to the caller instead
// of reaching the user's terminal.
#pragma once

#include <cstddef>
#include <functional>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace iso {

inline constexpr int kChildOutFd = 3, kChildStatusFd = 4;

struct ChildJob {
    std::string flag;              // the first argument that makes this program the child
    std::string path;              // what errors name
    std::vector<std::string> args; // the child's own arguments (a mode first)
    std::size_t memory_cap = 0;    // bytes the child may add to its address space (0: no cap)
    std::string input;             // written to the child's standard input
    std::string reader;            // who reads, for messages: "OpenVDB's reader"
    std::string memory_env;        // the variable that sets the cap in MiB, for messages
    std::string timeout_env;       // the variable that sets the timeout in seconds
    unsigned timeout_s = 120;      // the child's alarm, unless timeout_env says otherwise
};

// Starts the child, hands `consume` an istream over its product and returns
// its status after "ok". `consume` may throw: iso::Cancelled is passed on
// (the child is stopped), anything else becomes an error. A child that
// crashed, ran out of its memory or time, or reported an error gives an
// iso::Error naming job.path (with the last line the child wrote on its
// standard error when it died). `diagnostics`, when given, gets what the
// child wrote on its standard error (its first 1 MiB).
std::string run_child(const ChildJob& job, const std::function<void(std::istream&)>& consume,
                      std::string* diagnostics = nullptr);

// ---- in the child ----
// argv as run_child passes it: [name, flag, memory cap, timeout s, args...].
inline constexpr int kChildFirstArg = 4;
// Whether this process was started as the child `flag` (for an ELF
// constructor: glibc passes it argc and argv).
bool is_child(int argc, char** argv, const char* flag);
// Default signal dispositions (a host's crash handler must not keep the
// child alive), the alarm, and the memory cap, all from argv.
void child_begin(char** argv);
void child_write(int fd, const std::string& s);
// Everything readable from `fd` (the child's standard input, say).
std::string read_fd(int fd);

// Plain values on the child's product stream (the same program writes and
// reads them, so no byte order or layout is negotiated). child_get throws
// std::runtime_error saying "<who>'s output ended early" at a short read.
template <class T> void child_put(std::ostream& os, const T& v) {
    os.write(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T> T child_get(std::istream& is, const char* who) {
    T v{};
    is.read(reinterpret_cast<char*>(&v), sizeof v);
    if (!is) throw std::runtime_error(std::string(who) + "'s output ended early");
    return v;
}

// What a child may allocate when the caller has no better bound: `env` MiB
// when set, else half of physical memory.
std::size_t default_child_memory_cap(const char* env);

} // namespace iso
