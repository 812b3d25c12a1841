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

namespace iso {

// ---- in the child ------------------------------------------------------------

bool is_child(int argc, char** argv, const char* flag) {
    return argc >= kChildFirstArg && argv && argv[1] && std::strcmp(argv[1], flag) == 0;
}

void child_write(int fd, const std::string& s) {
    std::size_t done = 0;
    while (done < s.size()) {
        const ssize_t n = ::write(fd, s.data() + done, s.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return;
        done += std::size_t(n);
    }
}

std::string read_fd(int fd) {
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
std::string last_words(const std::string& err) {
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
[[noreturn]] void child_failed(const ChildJob& job, int st, const std::string& msg, const std::string& consume_error,
                               const std::string& err) {
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
    throw Error(job.path, job.reader + " failed on this file (corrupt or truncated?)" +
                              (said.empty() ? std::string() : "; it said: " + said));
}

// Reads the child's standard error on a thread of its own (a child that
// writes much there while we read its product must not block), keeping the
// first `keep` bytes.
class ErrorReader {
public:
    ErrorReader(int fd, std::size_t keep)
        : thread_([this, fd, keep] {
              char b[4096];
              for (;;) {
                  const ssize_t n = ::read(fd, b, sizeof b);
                  if (n < 0 && errno == EINTR) continue;
                  if (n <= 0) break;
                  if (text_.size() < keep) text_.append(b, std::min(std::size_t(n), keep - text_.size()));
              }
          }) {}
    // Waits for the child's end of the pipe to close.
    std::string take() {
        if (thread_.joinable()) thread_.join();
        return std::move(text_);
    }
    ~ErrorReader() {
        if (thread_.joinable()) thread_.join();
    }

private:
    std::string text_;
    std::thread thread_;
};

} // namespace

std::string run_child(const ChildJob& job, const std::function<void(std::istream&)>& consume,
                      std::string* diagnostics) {
    int in[2] = {-1, -1}, out[2] = {-1, -1}, status[2] = {-1, -1}, err[2] = {-1, -1};
    auto close_all = [&] {
        for (int* p : {in, out, status, err})
            for (int e = 0; e < 2; ++e)
                if (p[e] >= 0) ::close(std::exchange(p[e], -1));
    };
    pid_t pid = -1;
    try {
        make_pipe(in, job);
        make_pipe(out, job);
        make_pipe(status, job);
        make_pipe(err, job);
        pid = spawn(job, in[0], out[1], status[1], err[1]);
    } catch (...) {
        close_all();
        throw;
    }
    for (int* fd : {&in[0], &out[1], &status[1], &err[1]}) ::close(std::exchange(*fd, -1));
    ErrorReader errors(err[0], std::size_t(1) << 20);
    // The input first: the child reads all of it before it writes anything.
    // A child that died meanwhile gives EPIPE (ignored here: its status says why).
    {
        struct sigaction ign {
        }, old{};
        ign.sa_handler = SIG_IGN;
        ::sigaction(SIGPIPE, &ign, &old);
        child_write(in[1], job.input);
        ::sigaction(SIGPIPE, &old, nullptr);
        ::close(std::exchange(in[1], -1));
    }
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
    const std::string err_text = errors.take();
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
