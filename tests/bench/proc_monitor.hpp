// Runs a command as a child process and measures it from outside: wall time
// and peak resident memory of the child and of all its descendants (mpirun's
// ranks are children of mpirun, or of orted on other launch paths), polled
// from /proc every ~20 ms. For the scaling benchmark (scale_bench.cpp).
//
// Per process the peak is the kernel's own high-water mark (VmHWM), so a peak
// between two polls is not missed as long as the process is still alive at
// the next poll; a process that lives less than one poll interval may be
// missed (mpirun's ranks live for the whole run). The total is the largest sum
// of VmRSS over the tree seen at one poll (the memory in use at one time); the
// sum of the per-process peaks is reported too (an upper bound). For the child
// itself wait4()'s ru_maxrss is exact and is folded in.
//
// Written here: no Debian package measures a process tree's memory from C++
// (GNU time reports one process, and only after it ends).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <dirent.h>
#include <fcntl.h>
#include <fstream>
#include <map>
#include <set>
#include <spawn.h>
#include <sstream>
#include <string>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>
#include <vector>

extern char** environ;

namespace iso::bench {

struct ProcPeak {
    int pid = 0;
    std::string comm;      // process name (/proc/PID/comm, 15 characters at most), as last seen
    std::uint64_t hwm = 0; // bytes, VmHWM
};

struct MeasuredRun {
    bool started = false; // the program could be spawned
    int exit_code = -1;   // exit status, or 128 + signal
    bool timed_out = false;
    bool cancelled = false;
    double wall_s = 0;
    std::uint64_t total_peak = 0;   // largest sum of VmRSS over the tree at one poll
    std::uint64_t sum_of_peaks = 0; // sum of every process's VmHWM
    std::uint64_t child_maxrss = 0; // wait4's ru_maxrss of the direct child
    std::vector<ProcPeak> procs;    // every process seen, in order of first sight
    int polls = 0;
    std::string error; // why it could not be started
};

namespace detail {

// "VmRSS:" / "VmHWM:" of /proc/PID/status in bytes (0 when gone or a kernel thread).
inline void read_status(int pid, std::uint64_t& rss, std::uint64_t& hwm) {
    rss = hwm = 0;
    std::ifstream f("/proc/" + std::to_string(pid) + "/status");
    std::string line;
    while (std::getline(f, line)) {
        if (line.rfind("VmRSS:", 0) == 0)
            rss = std::stoull(line.substr(6)) * 1024;
        else if (line.rfind("VmHWM:", 0) == 0)
            hwm = std::stoull(line.substr(6)) * 1024;
    }
}

inline std::string read_comm(int pid) {
    std::ifstream f("/proc/" + std::to_string(pid) + "/comm");
    std::string s;
    std::getline(f, s);
    return s;
}

// Children of every thread of `pid` (/proc/PID/task/TID/children, Linux >= 3.5
// with CONFIG_PROC_CHILDREN; Debian's kernels have it). Falls back to scanning
// every /proc/N/stat for the parent id when that file is missing.
inline void children_of(int pid, std::vector<int>& out) {
    const std::string task = "/proc/" + std::to_string(pid) + "/task";
    DIR* d = ::opendir(task.c_str());
    if (!d) return;
    bool any_file = false;
    while (dirent* e = ::readdir(d)) {
        if (e->d_name[0] == '.') continue;
        std::ifstream f(task + "/" + e->d_name + "/children");
        if (!f) continue;
        any_file = true;
        int c;
        while (f >> c) out.push_back(c);
    }
    ::closedir(d);
    if (any_file) return;
    DIR* p = ::opendir("/proc");
    if (!p) return;
    while (dirent* e = ::readdir(p)) {
        if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
        std::ifstream f(std::string("/proc/") + e->d_name + "/stat");
        std::string s;
        std::getline(f, s);
        const auto close = s.rfind(')'); // comm may hold spaces and parentheses
        if (close == std::string::npos) continue;
        std::istringstream is(s.substr(close + 2));
        char state;
        int ppid = 0;
        is >> state >> ppid;
        if (ppid == pid) out.push_back(std::atoi(e->d_name));
    }
    ::closedir(p);
}

inline std::vector<int> descendants_and_self(int root) {
    std::vector<int> all{root};
    for (std::size_t i = 0; i < all.size(); ++i) children_of(all[i], all);
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    return all;
}

} // namespace detail

// Polls the tree under `pid` until it exits (reaping it), every `poll_ms`.
// `stop` (may be null) asks to kill the tree: SIGTERM to the child's process
// group, SIGKILL 3 s later. The child must lead its own process group (see
// run_measured) for the kill to reach mpirun's ranks.
inline void monitor_tree(int pid, MeasuredRun& r, int poll_ms, double timeout_s, const std::atomic<bool>* stop) {
    using clock = std::chrono::steady_clock;
    const auto t0 = clock::now();
    std::map<int, std::size_t> index; // pid -> position in r.procs
    double kill_sent = -1;
    int status = 0;
    rusage ru{};
    for (;;) {
        std::uint64_t sum_rss = 0;
        for (int p : detail::descendants_and_self(pid)) {
            std::uint64_t rss, hwm;
            detail::read_status(p, rss, hwm);
            if (rss == 0 && hwm == 0) continue; // gone, zombie, or a kernel thread
            auto it = index.find(p);
            if (it == index.end()) {
                it = index.emplace(p, r.procs.size()).first;
                r.procs.push_back({p, detail::read_comm(p), 0});
            }
            // The name is read again each time: a process first seen between
            // fork and exec still has its parent's name (mpirun's, ours).
            r.procs[it->second].comm = detail::read_comm(p);
            r.procs[it->second].hwm = std::max(r.procs[it->second].hwm, hwm);
            sum_rss += rss;
        }
        r.total_peak = std::max(r.total_peak, sum_rss);
        ++r.polls;
        const pid_t w = ::wait4(pid, &status, WNOHANG, &ru);
        const double t = std::chrono::duration<double>(clock::now() - t0).count();
        if (w == pid) {
            r.wall_s = t;
            break;
        }
        if (w < 0) { // not our child (should not happen): stop measuring
            r.wall_s = t;
            r.error = "lost the child process";
            return;
        }
        const bool want_stop = (stop && stop->load()) || (timeout_s > 0 && t > timeout_s);
        if (want_stop && kill_sent < 0) {
            r.timed_out = !(stop && stop->load());
            r.cancelled = !r.timed_out;
            ::kill(-pid, SIGTERM);
            kill_sent = t;
        } else if (kill_sent >= 0 && t - kill_sent > 3.0) {
            ::kill(-pid, SIGKILL);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(poll_ms));
    }
    if (kill_sent >= 0) ::kill(-pid, SIGKILL); // leftovers of the group (orphaned ranks)
    r.child_maxrss = std::uint64_t(ru.ru_maxrss) * 1024;
    if (!r.procs.empty() && r.procs.front().pid == pid)
        r.procs.front().hwm = std::max(r.procs.front().hwm, r.child_maxrss);
    r.sum_of_peaks = 0;
    for (const auto& p : r.procs) r.sum_of_peaks += p.hwm;
    r.total_peak = std::max(r.total_peak, r.procs.empty() ? 0 : r.procs.front().hwm);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
}

// Spawns argv[0] (searched in PATH) in its own process group with stdout and
// stderr going to the given files, and measures it (monitor_tree).
inline MeasuredRun run_measured(const std::vector<std::string>& argv, const std::string& stdout_path,
                                const std::string& stderr_path, int poll_ms = 20, double timeout_s = 0,
                                const std::atomic<bool>* stop = nullptr) {
    MeasuredRun r;
    if (argv.empty()) {
        r.error = "empty command";
        return r;
    }
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 2, stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawnattr_t at;
    posix_spawnattr_init(&at);
    posix_spawnattr_setflags(&at, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&at, 0);
    std::vector<char*> cargv;
    for (const auto& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
    cargv.push_back(nullptr);
    pid_t pid = 0;
    const int rc = ::posix_spawnp(&pid, cargv[0], &fa, &at, cargv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&at);
    if (rc != 0) {
        r.error = argv[0] + ": " + std::strerror(rc);
        return r;
    }
    r.started = true;
    monitor_tree(pid, r, poll_ms, timeout_s, stop);
    return r;
}

} // namespace iso::bench
