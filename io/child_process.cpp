#include "io/child_process.hpp"

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <thread>
#include <utility>

#include <ext/stdio_filebuf.h> // std::iostreams over a pipe's file descriptor (libstdc++)
#include <fcntl.h>
#include <malloc.h>
#include <spawn.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "io/error.hpp"
#include "io/process.hpp"
#include "io/progress.hpp"

extern char** environ;

// Is this an AddressSanitizer build? (GCC defines __SANITIZE_ADDRESS__, Clang answers __has_feature.)
#if defined(__SANITIZE_ADDRESS__)
#define ISOSCOPE_CHILD_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define ISOSCOPE_CHILD_ASAN 1
#endif
#endif
#ifndef ISOSCOPE_CHILD_ASAN
#define ISOSCOPE_CHILD_ASAN 0
#endif

// The plumbing below waits on another process: how many times its loops turn
// and which way its branches go can depend on timing. In the fuzz build it is
// left out of coverage, so that it adds no features that differ from run to
// run (tests/fuzz/smoke.sh must give the same verdict every time).
#if defined(__clang__)
#define ISOSCOPE_TIMING_DEPENDENT __attribute__((no_sanitize("coverage")))
#else
#define ISOSCOPE_TIMING_DEPENDENT
#endif

namespace iso {

// ---- in the child ------------------------------------------------------------

bool is_child(int argc, char** argv, const char* flag) {
    return argc >= kChildFirstArg && argv && argv[1] && std::strcmp(argv[1], flag) == 0;
}

ISOSCOPE_TIMING_DEPENDENT void child_write(int fd, const std::string& s) {
    std::size_t done = 0;
    while (done < s.size()) {
        const ssize_t n = ::write(fd, s.data() + done, s.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;
        done += std::size_t(n);
    }
}

ISOSCOPE_TIMING_DEPENDENT std::string read_fd(int fd) {
    std::string s;
    char b[4096];
    for (;;) {
        const ssize_t n = ::read(fd, b, sizeof b);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        s.append(b, std::size_t(n));
    }
    return s;
}

namespace {

// The child may add at most `cap` bytes to the address space it started
// with: a malformed file can make a library allocate without end (a
// truncated file had OpenVDB build a string of gigabytes), which then ends
// as bad_alloc, an error, instead of taking the machine's memory. Slack for
// the threads' stacks and malloc's arenas (at most two). Not under
// AddressSanitizer, whose shadow memory is terabytes of address space:
// run_child gives its allocator the cap instead.
void limit_memory(std::size_t cap) {
#if !ISOSCOPE_CHILD_ASAN
    if (cap == 0) return;
    mallopt(M_ARENA_MAX, 2);
    const std::size_t threads = std::max(1u, std::thread::hardware_concurrency());
    const std::size_t slack = (std::size_t(1) << 30) + threads * (std::size_t(16) << 20);
    const rlim_t as = rlim_t(process_status_bytes("VmSize:") + slack + cap);
    struct rlimit r;
    if (::getrlimit(RLIMIT_AS, &r) == 0 && (r.rlim_max == RLIM_INFINITY || as < r.rlim_max)) {
        r.rlim_cur = as;
        ::setrlimit(RLIMIT_AS, &r);
    }
#else
    (void)cap;
#endif
}

} // namespace

void child_begin(char** argv) {
    for (int sig : {SIGALRM, SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL, SIGPIPE}) std::signal(sig, SIG_DFL);
    // A malformed file must not hang the reader forever.
    ::alarm(unsigned(std::max(1l, std::strtol(argv[3], nullptr, 10))));
    limit_memory(std::size_t(std::strtoull(argv[2], nullptr, 10)));
}

std::size_t default_child_memory_cap(const char* env) {
    if (const char* e = std::getenv(env)) return std::size_t(std::max(1ll, std::atoll(e))) << 20;
    const std::size_t phys = physical_memory_bytes();
    return phys ? phys / 2 : std::size_t(8) << 30;
}

// ---- in the reading program ------------------------------------------------------

namespace {

// A pipe whose ends are above the descriptors the child's are copied to
// (0, kChildOutFd, kChildStatusFd), close-on-exec.
void make_pipe(int fds[2], const ChildJob& job) {
    int p[2];
    if (::pipe2(p, O_CLOEXEC) != 0)
        throw Error(job.path, "cannot start " + job.reader + "'s process: " + std::strerror(errno));
    for (int e = 0; e < 2; ++e) {
        fds[e] = ::fcntl(p[e], F_DUPFD_CLOEXEC, 10);
        ::close(p[e]);
    }
    if (fds[0] < 0 || fds[1] < 0) {
        for (int e = 0; e < 2; ++e)
            if (fds[e] >= 0) ::close(fds[e]);
        throw Error(job.path, "cannot start " + job.reader + "'s process: no file descriptors left");
    }
}

// The environment as it is; under AddressSanitizer (no address-space cap
// there, limit_memory) the child's sanitizer gets the cap instead: single
// allocations above it fail (bad_alloc, an error), and a resident size
// above it plus the program ends the child.
std::vector<std::string> child_environment(std::size_t cap) {
    std::vector<std::string> env;
    for (char** e = environ; e && *e; ++e) env.emplace_back(*e);
#if ISOSCOPE_CHILD_ASAN
    if (cap) {
        const std::string mib = std::to_string((cap >> 20) + 1);
        const std::string add = "allocator_may_return_null=1:max_allocation_size_mb=" + mib +
                                ":hard_rss_limit_mb=" + std::to_string((cap >> 20) + 2048);
        auto it =
            std::find_if(env.begin(), env.end(), [](const std::string& e) { return e.rfind("ASAN_OPTIONS=", 0) == 0; });
        if (it == env.end())
            env.push_back("ASAN_OPTIONS=" + add);
        else
            *it += (it->size() > 13 ? ":" : "") + add;
    }
#else
    (void)cap;
#endif
    return env;
}

unsigned timeout_of(const ChildJob& job) {
    if (const char* e = job.timeout_env.empty() ? nullptr : std::getenv(job.timeout_env.c_str()))
        return unsigned(std::max(1, std::atoi(e)));
    return job.timeout_s;
}

// Spawns the child with its pipes' far ends; returns its pid.
pid_t spawn(const ChildJob& job, int in, int out, int status, int err) {
    std::vector<std::string> argv_s{"isoscope-child", job.flag, std::to_string(job.memory_cap),
                                    std::to_string(timeout_of(job))};
    argv_s.insert(argv_s.end(), job.args.begin(), job.args.end());
    std::vector<char*> argv;
    for (auto& a : argv_s) argv.push_back(a.data());
    argv.push_back(nullptr);
    std::vector<std::string> env_s = child_environment(job.memory_cap);
    std::vector<char*> envp;
    for (auto& e : env_s) envp.push_back(e.data());
    envp.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, in, STDIN_FILENO);
    posix_spawn_file_actions_adddup2(&fa, out, kChildOutFd);
    posix_spawn_file_actions_adddup2(&fa, status, kChildStatusFd);
    posix_spawn_file_actions_adddup2(&fa, err, STDERR_FILENO);
    posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    pid_t pid = -1;
    std::fflush(nullptr);
    const int rc = ::posix_spawn(&pid, "/proc/self/exe", &fa, nullptr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) throw Error(job.path, "cannot start " + job.reader + "'s process: " + std::strerror(rc));
    return pid;
}

// The last non-empty line of what the child wrote on its standard error,
// without a program name before it (an assertion's "prog: file:line: ...").
ISOSCOPE_TIMING_DEPENDENT std::string last_words(const std::string& err) {
    std::size_t end = err.find_last_not_of(" \n\r\t");
    if (end == std::string::npos) return {};
    const std::size_t begin = err.rfind('\n', end);
    std::string line =
        err.substr(begin == std::string::npos ? 0 : begin + 1, end + 1 - (begin == std::string::npos ? 0 : begin + 1));
    if (line.rfind("isoscope-child: ", 0) == 0) line = line.substr(16);
    // glibc's "file:line: function: Assertion `x' failed." made short: the
    // assertion, then where (the file's name and line).
    if (const auto a = line.find(": Assertion `"); a != std::string::npos) {
        const std::string where = line.substr(0, line.find(": "));
        line = line.substr(a + 2) + " (" + where.substr(where.rfind('/') + 1) + ")";
    }
    if (line.size() > 300) line = line.substr(0, 300) + "...";
    return line;
}

// What the child's end says, as an error naming the file.
[[noreturn]] ISOSCOPE_TIMING_DEPENDENT void child_failed(const ChildJob& job, int st, const std::string& msg,
                                                         const std::string& consume_error, const std::string& err) {
    if (WIFEXITED(st) && WEXITSTATUS(st) >= 2 && !msg.empty()) {
        if (msg.find("bad_alloc") != std::string::npos)
            throw Error(job.path, job.reader + " needed more than the " + std::to_string(job.memory_cap >> 20) +
                                      " MiB allowed to it (corrupt file? " + job.memory_env +
                                      " sets the limit in MiB)");
        throw Error(job.path, msg);
    }
    if (WIFSIGNALED(st) && WTERMSIG(st) == SIGALRM)
        throw Error(job.path, job.reader + " did not finish in time (corrupt file? " + job.timeout_env +
                                  " sets the limit in seconds)");
    if (WIFEXITED(st) && WEXITSTATUS(st) == 0)
        throw Error(job.path, "cannot take the result of " + job.reader + "'s process: " + consume_error);
    const std::string said = last_words(err);
    const std::string how = WIFSIGNALED(st) ? std::string(" (it ended with ") + ::strsignal(WTERMSIG(st)) + ")" : "";
    throw Error(job.path, job.reader + " failed on this file (corrupt or truncated?)" + how +
                              (said.empty() ? std::string() : "; it said: " + said));
}

// A file in memory (memfd) holding `text`, read from its start, for the
// child's standard input; an empty one for its standard error. Files, not
// pipes: nothing blocks, no thread drains them, and what the program does
// does not depend on how the kernel split the bytes (the deterministic fuzz
// smoke counts on it).
int memory_file(const ChildJob& job, const char* name, const std::string& text) {
    // Above the descriptors the child's are copied to (0-4), close-on-exec.
    const int created = ::memfd_create(name, MFD_CLOEXEC);
    const int fd = created < 0 ? -1 : ::fcntl(created, F_DUPFD_CLOEXEC, 10);
    if (created >= 0) ::close(created);
    if (fd < 0) throw Error(job.path, "cannot start " + job.reader + "'s process: " + std::strerror(errno));
    child_write(fd, text);
    ::lseek(fd, 0, SEEK_SET);
    return fd;
}

// The first `keep` bytes of a memory file.
ISOSCOPE_TIMING_DEPENDENT std::string read_memory_file(int fd, std::size_t keep) {
    ::lseek(fd, 0, SEEK_SET);
    std::string s(keep, '\0');
    std::size_t got = 0;
    while (got < keep) {
        const ssize_t n = ::read(fd, s.data() + got, keep - got);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        got += std::size_t(n);
    }
    s.resize(got);
    return s;
}

} // namespace

ISOSCOPE_TIMING_DEPENDENT std::string run_child(const ChildJob& job, const std::function<void(std::istream&)>& consume,
                                                std::string* diagnostics) {
    int in = -1, err = -1, out[2] = {-1, -1}, status[2] = {-1, -1};
    auto close_all = [&] {
        for (int* p : {out, status})
            for (int e = 0; e < 2; ++e)
                if (p[e] >= 0) ::close(std::exchange(p[e], -1));
        for (int* fd : {&in, &err})
            if (*fd >= 0) ::close(std::exchange(*fd, -1));
    };
    pid_t pid = -1;
    try {
        in = memory_file(job, "isoscope-child-input", job.input);
        err = memory_file(job, "isoscope-child-stderr", "");
        make_pipe(out, job);
        make_pipe(status, job);
        pid = spawn(job, in, out[1], status[1], err);
    } catch (...) {
        close_all();
        throw;
    }
    for (int* fd : {&out[1], &status[1]}) ::close(std::exchange(*fd, -1));
    std::string consume_error;
    bool cancelled = false;
    {
        // Owns out[0]: closed when the product is consumed or consuming failed
        // (a child still writing then gets EPIPE and ends).
        __gnu_cxx::stdio_filebuf<char> buf(std::exchange(out[0], -1), std::ios::in, 1 << 16);
        std::istream is(&buf);
        try {
            consume(is);
        } catch (const Cancelled&) {
            cancelled = true;
            ::kill(pid, SIGKILL);
        } catch (const std::exception& e) {
            consume_error = e.what(); // the child, still writing, gets EPIPE and ends
        }
    }
    const std::string msg = read_fd(status[0]);
    int st = 0;
    while (::waitpid(pid, &st, 0) < 0 && errno == EINTR) {}
    const std::string err_text = read_memory_file(err, std::size_t(1) << 20);
    close_all();
    if (diagnostics) *diagnostics = err_text;
    if (cancelled) throw Cancelled(job.path);
    if (WIFEXITED(st) && WEXITSTATUS(st) == 0 && consume_error.empty()) {
        if (msg.rfind("ok", 0) != 0) throw Error(job.path, job.reader + "'s process gave no result");
        return msg.substr(std::min<std::size_t>(msg.size(), 3));
    }
    child_failed(job, st, msg, consume_error, err_text);
}

} // namespace iso
