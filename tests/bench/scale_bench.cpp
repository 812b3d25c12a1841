// Out-of-core / MPI scaling benchmark: `isoscope mesh` streaming
// with a memory budget, as one process and under `mpirun -np N`, against
// VTK's Flying Edges holding the whole volume, on generated CT-like int16
// volumes of 2 GiB and 8 GiB (tests/bench/scale_volume.hpp). Every run is
// its own child process measured from outside (proc_monitor.hpp): wall time,
// peak resident memory per rank and in total, throughput, triangles, bytes.
//
//   scale_bench [--quick] [--out DIR] [--data DIR] [--sizes 1024,2048x2048x1024]
//               [--ranks 1,2,4] [--reps N] [--reps-large N] [--warmup N] [--iso V] [--memory MiB] [--slack MiB]
//               [--threads N] [--isoscope PATH] [--mpirun PATH] [--isoscope-args T] [--mpirun-args T]
//               [--isoscope-mpi-args T]
//               [--no-single] [--no-mpi] [--no-fe] [--fe-max-gib G] [--cache warm|cold]
//               [--timeout S] [--keep-output] [--generate-only]
//
// The command lines are data (docs/scaling.md): templates with {isoscope},
// {in}, {iso}, {memory}, {threads}, {ranks}, {out} filled per run, so the
// same program runs today's in-memory CLI or, once merged, `--memory/--stream`
// and the MPI build. A configuration that fails (a flag the CLI does not
// know, no mpirun) is recorded as failed in the table and the rest goes on.
//
// Writes OUT/scale_bench.md, OUT/scale_bench.csv and, with gnuplot,
// OUT/scale_time.png and OUT/scale_memory.png.
#include <array>
#include <atomic>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <thread>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/utsname.h>
#include <unistd.h>

#include <tbb/global_control.h>
#include <vtkFlyingEdges3D.h>
#include <vtkImageData.h>
#include <vtkNIFTIImageReader.h>
#include <vtkNew.h>
#include <vtkPolyData.h>

#include "bench_util.hpp"
#include "proc_monitor.hpp"
#include "scale_volume.hpp"

using namespace iso;
using namespace iso::bench;
namespace fs = std::filesystem;

namespace iso::bench {
void set_vtk_threads(int n); // vtk_threads.cpp
}

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_sigint(int) { g_stop = true; }

constexpr const char* kDefaultIsoscopeArgs =
    "mesh {in} --iso {iso} --memory {memory} --stream --threads {threads} -o {out}/surface.pvtp";

std::string default_mpirun_args() {
    // --bind-to none: OpenMPI binds each rank to one core by default (np <= 2),
    // which would leave a single rank's second thread without a core.
    std::string s = "--oversubscribe --bind-to none -np {ranks}";
    if (::getuid() == 0) s += " --allow-run-as-root"; // OpenMPI refuses root otherwise
    return s;
}

struct Args {
    bool quick = false, generate_only = false, keep_output = false;
    bool single = true, mpi = true, fe = true;
    std::string out = "bench-results/scale", data = "/tmp/isoscope-scale";
    std::vector<std::array<std::int64_t, 3>> sizes;
    std::vector<int> ranks;
    int reps = -1, reps_large = 1, warmup = 1;
    double iso = 300.5;
    int memory = 1024, slack = 256;
    int threads = int(std::max(1u, std::thread::hardware_concurrency()));
    double fe_max_gib = 2.0;
    std::string cache = "warm";
    double timeout = 3600;
    std::string isoscope = ISOSCOPE_CLI, mpirun = "mpirun";
    std::string isoscope_args = kDefaultIsoscopeArgs, mpirun_args = default_mpirun_args();
    std::optional<std::string> isoscope_mpi_args; // isoscope's arguments under mpirun; default: isoscope_args
    // child mode (Flying Edges)
    std::string one, in;
};

[[noreturn]] void usage(const std::string& why) {
    std::cerr
        << "scale_bench: " << why << "\n"
        << "usage: scale_bench [--quick] [--out DIR] [--data DIR] [--sizes N|WxHxD,...] [--ranks 1,2,4] [--reps N]\n"
           "                   [--reps-large N] [--warmup N] [--iso V] [--memory MiB] [--slack MiB] [--threads N]\n"
           "                   [--isoscope PATH] [--mpirun PATH] [--isoscope-args T] [--mpirun-args T] "
           "[--isoscope-mpi-args T]\n"
           "                   [--no-single] [--no-mpi] [--no-fe] [--fe-max-gib G] [--cache warm|cold]\n"
           "                   [--timeout S] [--keep-output] [--generate-only]\n";
    std::exit(2);
}

std::array<std::int64_t, 3> parse_size(const std::string& s) {
    std::array<std::int64_t, 3> d{};
    if (std::sscanf(s.c_str(), "%ldx%ldx%ld", &d[0], &d[1], &d[2]) == 3) return d;
    char* end = nullptr;
    const long n = std::strtol(s.c_str(), &end, 10);
    if (end && *end == 0 && n > 1) return {n, n, n};
    usage("--sizes: '" + s + "' is not N or WxHxD");
}

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> out;
    std::string cur;
    std::istringstream is(s);
    while (std::getline(is, cur, sep))
        if (!cur.empty()) out.push_back(cur);
    return out;
}

// Splits a template into words (whitespace; single or double quotes group),
// then fills the placeholders in each word: a path with spaces stays one argument.
std::vector<std::string> expand(const std::string& tmpl, const std::map<std::string, std::string>& vars) {
    std::vector<std::string> words;
    std::string cur;
    bool have = false;
    char quote = 0;
    for (char c : tmpl) {
        if (quote) {
            if (c == quote)
                quote = 0;
            else
                cur += c;
        } else if (c == '\'' || c == '"') {
            quote = c;
            have = true;
        } else if (std::isspace(static_cast<unsigned char>(c))) {
            if (have || !cur.empty()) words.push_back(cur);
            cur.clear();
            have = false;
        } else {
            cur += c;
        }
    }
    if (quote) throw Error("command template", "unbalanced quote in '" + tmpl + "'");
    if (have || !cur.empty()) words.push_back(cur);
    for (auto& w : words) {
        std::string r;
        for (std::size_t i = 0; i < w.size(); ++i) {
            if (w[i] == '{') {
                const auto close = w.find('}', i);
                if (close != std::string::npos) {
                    const auto it = vars.find(w.substr(i + 1, close - i - 1));
                    if (it == vars.end())
                        throw Error("command template", "unknown placeholder " + w.substr(i, close - i + 1));
                    r += it->second;
                    i = close;
                    continue;
                }
            }
            r += w[i];
        }
        w = r;
    }
    return words;
}

std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& w : v) {
        if (!s.empty()) s += ' ';
        s += w.find_first_of(" \t'\"") == std::string::npos ? w : "'" + w + "'";
    }
    return s;
}

std::string slurp(const std::string& path) {
    std::ifstream f(path);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

std::uint64_t tree_bytes(const fs::path& dir) {
    std::uint64_t n = 0;
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
         it.increment(ec))
        if (it->is_regular_file(ec)) n += it->file_size(ec);
    return n;
}

// Fraction of the file's pages in the page cache (mincore over a mapping
// that is never touched, so it adds nothing to anyone's RSS).
double cached_fraction(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY);
    if (fd < 0) return -1;
    const auto size = fs::file_size(path);
    void* m = size ? ::mmap(nullptr, size, PROT_READ, MAP_SHARED, fd, 0) : MAP_FAILED;
    ::close(fd);
    if (m == MAP_FAILED) return -1;
    const std::size_t page = std::size_t(::sysconf(_SC_PAGESIZE));
    std::vector<unsigned char> vec((size + page - 1) / page);
    double f = -1;
    if (::mincore(m, size, vec.data()) == 0)
        f = double(std::count_if(vec.begin(), vec.end(), [](unsigned char c) { return c & 1; })) / double(vec.size());
    ::munmap(m, size);
    return f;
}

// Cold cache without root: ask the kernel to drop this file's clean pages
// (POSIX_FADV_DONTNEED works for any reader; /proc/sys/vm/drop_caches would
// need root and would also drop every other engineer's cache).
void evict_file(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY);
    if (fd < 0) return;
    ::fdatasync(fd);
    ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
    ::close(fd);
}

// ---- child: vtkFlyingEdges3D on the whole volume ---------------------------

int run_fe(const Args& a) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, std::size_t(a.threads));
    set_vtk_threads(a.threads);
    const double t0 = now_s();
    // VTK's own NIfTI reader: one copy of the volume in a vtkImageData, as a
    // VTK pipeline holds it (same samples; the orientation does not change the surface).
    vtkNew<vtkNIFTIImageReader> reader;
    reader->SetFileName(a.in.c_str());
    reader->Update();
    vtkImageData* img = reader->GetOutput();
    int dims[3];
    img->GetDimensions(dims);
    if (std::int64_t(dims[0]) * dims[1] * dims[2] < 8) throw Error(a.in, "vtkNIFTIImageReader read no voxels");
    const double t1 = now_s();
    vtkNew<vtkFlyingEdges3D> fe;
    fe->SetInputData(img);
    fe->SetValue(0, a.iso);
    fe->ComputeNormalsOn(); // as isosurface_bench and our extractor (normals are part of the output)
    fe->ComputeGradientsOff();
    fe->ComputeScalarsOff();
    fe->Update();
    const double t2 = now_s();
    std::cout << std::setprecision(6) << "RESULT read_s=" << t1 - t0 << " fe_s=" << t2 - t1
              << " tris=" << fe->GetOutput()->GetNumberOfCells() << " verts=" << fe->GetOutput()->GetNumberOfPoints()
              << "\n";
    return 0;
}

// ---- driver -----------------------------------------------------------------

struct Row {
    std::string config, volume;
    std::uint64_t voxels = 0;
    int ranks = 1, threads = 1, reps = 0;
    int budget = 0; // MiB; 0 = no budget in the command line
    std::vector<double> walls;
    double peak_rank = 0, total = 0, sum_peaks = 0; // MiB, worst over the measured runs
    std::vector<double> rank_peaks;                 // MiB, per rank, of the worst run
    double cached = -1;                             // page-cache fraction of the input before the first measured run
    std::uint64_t tris = 0, out_bytes = 0;
    std::string status = "ok", command;
    double wall() const { return median(walls); }
    double vps() const { return walls.empty() ? 0 : double(voxels) / wall(); }
};

// Shortest exact-enough text of a number for a command line (300.5, not 300.500000).
std::string num(double v) {
    std::ostringstream s;
    s << std::setprecision(10) << v;
    return s.str();
}

std::string fmt(double v, int prec) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(prec) << v;
    return s.str();
}

// The first line of a failed run's output that says something: CLI11 puts
// the reason first ("The following arguments were not expected: ..."), and
// OpenMPI frames its reports in lines of dashes, after the rank's own message.
std::string first_message(const std::string& text) {
    std::istringstream is(text);
    std::string line;
    while (std::getline(is, line)) {
        while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
        if (line.find_first_not_of(" -*=\t") == std::string::npos) continue;
        for (auto& c : line)
            if (c == '|' || c == ',') c = ';'; // keep the table and the CSV intact
        return line.size() > 200 ? line.substr(0, 200) + "..." : line;
    }
    return "(no output)";
}

class Bench {
public:
    explicit Bench(Args a) : a_(std::move(a)) {}

    int run() {
        fs::create_directories(a_.out);
        out_ = fs::canonical(a_.out);
        std::vector<std::pair<ScaleVolumeParams, std::string>> volumes;
        for (const auto& d : a_.sizes) {
            ScaleVolumeParams p;
            p.dims = d;
            bool reused = false;
            const double t0 = now_s();
            const std::string path = ensure_scale_volume(p, a_.data, reused, progress("generating " + p.name()));
            const double dt = now_s() - t0;
            std::cerr << "\n";
            gen_notes_.push_back(p.name() + ".nii (" + fmt(double(p.voxels() * 2) / (1 << 30), 2) + " GiB): " +
                                 (reused ? "reused (sidecar matches)"
                                         : "generated in " + fmt(dt, 1) + " s (" +
                                               fmt(double(p.voxels()) / dt / 1e6, 1) + " Mvoxel/s)"));
            std::cout << gen_notes_.back() << "\n";
            volumes.emplace_back(p, path);
            if (g_stop) break;
        }
        if (a_.generate_only || g_stop) return g_stop ? 130 : 0;

        for (const auto& [p, path] : volumes) {
            const bool large = p.voxels() * 2 > (std::uint64_t(4) << 30);
            const int reps = large ? a_.reps_large : a_.reps;
            if (a_.single) measure("isoscope", p, path, 1, reps);
            if (a_.mpi)
                for (int n : a_.ranks) measure("isoscope-mpi", p, path, n, reps);
            if (a_.fe && double(p.voxels() * 2) <= a_.fe_max_gib * double(1 << 30) + 1)
                measure("vtkFlyingEdges3D", p, path, 1, reps);
            if (g_stop) break;
        }
        write_outputs();
        return g_stop ? 130 : 0;
    }

private:
    ProgressFn progress(std::string what) {
        return [what, last = -1](double f, std::string_view) mutable {
            const int pct = int(f * 100);
            if (pct != last) {
                last = pct;
                std::cerr << "\r" << what << " " << pct << "%" << std::flush;
            }
            return !g_stop.load();
        };
    }

    void measure(const std::string& config, const ScaleVolumeParams& p, const std::string& in, int ranks, int reps) {
        Row r;
        r.config = config;
        r.volume = p.name();
        r.voxels = p.voxels();
        r.ranks = ranks;
        r.threads = config == "vtkFlyingEdges3D" ? a_.threads : std::max(1, a_.threads / ranks);
        const bool ours = config != "vtkFlyingEdges3D";
        const std::string& tmpl = config == "isoscope-mpi" ? mpi_args() : a_.isoscope_args;
        r.budget = ours && tmpl.find("{memory}") != std::string::npos ? a_.memory : 0;
        const fs::path dir = out_ / "runs" / (config + "-" + p.name() + "-np" + std::to_string(ranks));
        std::vector<std::string> argv;
        try {
            const std::map<std::string, std::string> vars = {{"isoscope", a_.isoscope},
                                                             {"in", in},
                                                             {"iso", num(a_.iso)},
                                                             {"memory", std::to_string(a_.memory)},
                                                             {"threads", std::to_string(r.threads)},
                                                             {"ranks", std::to_string(ranks)},
                                                             {"out", (dir / "out").string()}};
            if (config == "vtkFlyingEdges3D") {
                argv = {fs::canonical("/proc/self/exe").string(),
                        "--one",
                        "fe",
                        "--in",
                        in,
                        "--iso",
                        num(a_.iso),
                        "--threads",
                        std::to_string(r.threads)};
            } else {
                argv = expand(tmpl, vars);
                argv.insert(argv.begin(), a_.isoscope);
                if (config == "isoscope-mpi") {
                    auto m = expand(a_.mpirun_args, vars);
                    m.insert(m.begin(), a_.mpirun);
                    argv.insert(argv.begin(), m.begin(), m.end());
                }
            }
        } catch (const std::exception& e) {
            r.status = std::string("failed: ") + e.what();
            rows_.push_back(r);
            return;
        }
        r.command = join(argv);
        // The ranks are the processes running the measured program (not mpirun/orted).
        const std::string rank_comm =
            fs::path(config == "vtkFlyingEdges3D" ? argv[0] : a_.isoscope).filename().string().substr(0, 15);
        for (int rep = 1 - a_.warmup; rep <= reps && !g_stop; ++rep) { // rep <= 0: warm-up, not counted
            std::error_code ec;
            fs::remove_all(dir, ec);
            fs::create_directories(dir / "out");
            if (a_.cache == "cold") evict_file(in);
            const double cached = cached_fraction(in);
            std::cerr << config << " " << p.name() << " np " << ranks
                      << (rep <= 0 ? " warm-up" : " rep " + std::to_string(rep)) << " ... " << std::flush;
            const MeasuredRun m = run_measured(argv, (dir / "stdout.txt").string(), (dir / "stderr.txt").string(), 20,
                                               a_.timeout, &g_stop);
            const std::string out = slurp((dir / "stdout.txt").string()), err = slurp((dir / "stderr.txt").string());
            if (!m.started || m.exit_code != 0 || m.timed_out || m.cancelled) {
                r.status = !m.started    ? "failed to start: " + m.error
                           : m.timed_out ? "timed out after " + fmt(a_.timeout, 0) + " s"
                           : m.cancelled ? "cancelled"
                                         : "failed (exit " + std::to_string(m.exit_code) +
                                               "): " + first_message(err.empty() ? out : err);
                std::cerr << r.status << "\n";
                r.walls.clear();
                break;
            }
            std::cerr << fmt(m.wall_s, 2) << " s\n";
            // Triangles: the CLI's summary line ("NAME: N triangles, ..."), or the FE child's RESULT.
            std::uint64_t tris = 0;
            std::smatch sm;
            if (std::regex_search(out, sm, std::regex(R"(tris=([0-9]+))")) ||
                std::regex_search(out, sm, std::regex(R"(([0-9]+) triangles)")))
                tris = std::stoull(sm[1]);
            if (rep <= 0) {
                r.tris = tris;
                continue;
            }
            if (r.walls.empty()) r.cached = cached;
            r.walls.push_back(m.wall_s);
            r.tris = tris;
            r.out_bytes = tree_bytes(dir / "out");
            std::vector<double> ranks_mib;
            for (const auto& pr : m.procs)
                if (pr.comm == rank_comm) ranks_mib.push_back(double(pr.hwm) / (1 << 20));
            const double worst = ranks_mib.empty() ? 0 : *std::max_element(ranks_mib.begin(), ranks_mib.end());
            if (worst >= r.peak_rank) {
                r.peak_rank = worst;
                r.rank_peaks = ranks_mib;
            }
            r.total = std::max(r.total, double(m.total_peak) / (1 << 20));
            r.sum_peaks = std::max(r.sum_peaks, double(m.sum_of_peaks) / (1 << 20));
            if (ranks_mib.size() != std::size_t(ranks))
                r.status = "ok; saw " + std::to_string(ranks_mib.size()) + " '" + rank_comm + "' processes, expected " +
                           std::to_string(ranks);
        }
        r.reps = int(r.walls.size());
        if (!a_.keep_output) {
            std::error_code ec;
            fs::remove_all(dir / "out", ec); // surfaces of GiBs; the logs stay
        }
        rows_.push_back(r);
    }

    const std::string& mpi_args() const { return a_.isoscope_mpi_args ? *a_.isoscope_mpi_args : a_.isoscope_args; }

    std::string check(const Row& r) const {
        if (r.walls.empty()) return "-";
        if (r.budget == 0) return "n/a";
        return r.peak_rank <= r.budget + a_.slack ? "PASS" : "FAIL";
    }

    void write_outputs() {
        std::ostringstream md;
        utsname u{};
        ::uname(&u);
        md << "# Out-of-core and MPI extraction (scale_bench)\n\n";
        md << "- machine: " << std::thread::hardware_concurrency() << " cores, " << mem_total_gib() << " GiB RAM, "
           << u.sysname << " " << u.release << "\n";
        md << "- iso " << a_.iso
           << " HU (cancellous and cortical bone, vessels, bright objects; half-integer so that no int16 sample ties "
              "it)\n";
        md << "- memory budget " << a_.memory
           << " MiB per process (`--memory`, where the command has {memory}); check: peak "
           << "RSS of every rank <= budget + " << a_.slack << " MiB (the stated constant)\n";
        md << "- vtkFlyingEdges3D reads the volume (vtkNIFTIImageReader) and extracts with normals, but writes "
              "nothing; "
              "isoscope's wall time includes writing its surface\n";
        md << "- each configuration: " << a_.warmup << " warm-up run(s) (not counted) + " << a_.reps
           << " measured run(s), " << a_.reps_large
           << " for volumes over 4 GiB; wall = median; peaks = worst measured run\n";
        md << "- page cache: "
           << (a_.cache == "cold" ? "cold (input file evicted with posix_fadvise DONTNEED before every run)"
                                  : "warm (no eviction: after the warm-up the input is in the page cache when it fits; "
                                    "'cached' column)")
           << "\n";
        md << "- memory polled from /proc/PID/status every 20 ms over the child and its descendants: per rank = VmHWM "
              "of each "
              "rank process, total = largest sum of VmRSS at one poll (mpirun/orted included)\n";
        md << "- isoscope command: `" << a_.isoscope << " " << a_.isoscope_args << "`; under MPI: `" << a_.mpirun << " "
           << a_.mpirun_args << " " << a_.isoscope << " " << mpi_args() << "`\n";
        for (const auto& g : gen_notes_) md << "- input " << g << "\n";
        md << "\n| config | volume | ranks | threads/rank | budget MiB | wall s (min-max) | peak RSS/rank MiB (each) | "
              "total MiB | peak - budget MiB | Mvoxel/s | triangles | output MiB | cached | check | status |\n"
           << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        std::ofstream csv(out_ / "scale_bench.csv");
        csv << "config,volume,voxels,ranks,threads_per_rank,budget_mib,reps,wall_s,wall_min_s,wall_max_s,peak_rank_mib,"
               "total_mib,sum_of_peaks_mib,peak_minus_budget_mib,voxels_per_s,triangles,output_bytes,cached_fraction,"
               "check,"
               "status,command\n";
        for (const auto& r : rows_) {
            const bool ok = !r.walls.empty();
            std::string each;
            for (double v : r.rank_peaks) each += (each.empty() ? "" : "/") + fmt(v, 0);
            const double over = r.peak_rank - r.budget;
            md << "| " << r.config << " | " << r.volume << " | " << r.ranks << " | " << r.threads << " | "
               << (r.budget ? std::to_string(r.budget) : "-") << " | "
               << (ok ? fmt(r.wall(), 2) + " (" + fmt(*std::min_element(r.walls.begin(), r.walls.end()), 2) + "-" +
                            fmt(*std::max_element(r.walls.begin(), r.walls.end()), 2) + ")"
                      : "-")
               << " | " << (ok ? fmt(r.peak_rank, 0) + (r.rank_peaks.size() > 1 ? " (" + each + ")" : "") : "-")
               << " | " << (ok ? fmt(r.total, 0) : "-") << " | " << (ok && r.budget ? fmt(over, 0) : "-") << " | "
               << (ok ? fmt(r.vps() / 1e6, 1) : "-") << " | " << (ok ? std::to_string(r.tris) : "-") << " | "
               << (ok && r.config != "vtkFlyingEdges3D" ? fmt(double(r.out_bytes) / (1 << 20), 1) : "-") << " | "
               << (r.cached >= 0 ? fmt(100 * r.cached, 0) + "%" : "-") << " | " << check(r) << " | " << r.status
               << " |\n";
            csv << r.config << "," << r.volume << "," << r.voxels << "," << r.ranks << "," << r.threads << ","
                << r.budget << "," << r.reps << "," << (ok ? fmt(r.wall(), 3) : "") << ","
                << (ok ? fmt(*std::min_element(r.walls.begin(), r.walls.end()), 3) : "") << ","
                << (ok ? fmt(*std::max_element(r.walls.begin(), r.walls.end()), 3) : "") << ","
                << (ok ? fmt(r.peak_rank, 1) : "") << "," << (ok ? fmt(r.total, 1) : "") << ","
                << (ok ? fmt(r.sum_peaks, 1) : "") << "," << (ok && r.budget ? fmt(over, 1) : "") << ","
                << (ok ? fmt(r.vps(), 0) : "") << "," << (ok ? std::to_string(r.tris) : "") << ","
                << (ok ? std::to_string(r.out_bytes) : "") << "," << (r.cached >= 0 ? fmt(r.cached, 3) : "") << ","
                << check(r) << "," << r.status << ",\"" << r.command << "\"\n";
        }
        // Same volume, same iso, no sample tying it: every extraction must give
        // Flying Edges' triangle count (docs/isosurface.md), streamed, split
        // over ranks or not. A difference is a finding, not a measurement.
        md << "\n";
        for (const auto& fe : rows_) {
            if (fe.config != "vtkFlyingEdges3D" || fe.walls.empty()) continue;
            std::string differ;
            int same = 0;
            for (const auto& r : rows_)
                if (r.volume == fe.volume && &r != &fe && !r.walls.empty()) {
                    if (r.tris == fe.tris)
                        ++same;
                    else
                        differ +=
                            " " + r.config + " np " + std::to_string(r.ranks) + " (" + std::to_string(r.tris) + ")";
                }
            if (differ.empty() && same == 0)
                md << "Triangles on " << fe.volume << ": no isoscope run to compare with vtkFlyingEdges3D's " << fe.tris
                   << ".\n";
            else if (differ.empty())
                md << "Triangles on " << fe.volume << ": all " << same << " isoscope runs give " << fe.tris
                   << ", the same as vtkFlyingEdges3D.\n";
            else
                md << "Triangles on " << fe.volume << ": DIFFERENT from vtkFlyingEdges3D (" << fe.tris << "):" << differ
                   << ".\n";
        }
        int pass = 0, fail = 0, failed_runs = 0;
        for (const auto& r : rows_) {
            pass += check(r) == "PASS";
            fail += check(r) == "FAIL";
            failed_runs += r.walls.empty();
        }
        md << "\nMemory check (peak RSS of every rank <= " << a_.memory << " + " << a_.slack << " MiB): " << pass
           << " PASS, " << fail << " FAIL" << (pass + fail == 0 ? " (no run carried a budget)" : "") << "; "
           << failed_runs << " configuration(s) did not run to the end.\n";
        md << "\nCommands as run:\n\n";
        for (const auto& r : rows_)
            if (!r.command.empty())
                md << "- " << r.config << " " << r.volume << " np " << r.ranks << ": `" << r.command << "`\n";
        const std::string text = md.str();
        std::ofstream(out_ / "scale_bench.md") << text;
        std::cout << "\n" << text;
        csv.close();
        plot();
        std::cout << "\nwrote " << (out_ / "scale_bench.md").string() << " and .csv\n";
    }

    static std::string mem_total_gib() {
        std::ifstream f("/proc/meminfo");
        std::string k;
        double kb = 0;
        f >> k >> kb;
        return fmt(kb / (1 << 20), 1);
    }

    // Per (config, volume) series: ranks, wall s, Mvoxel/s, peak/rank MiB, total MiB.
    void plot() {
        if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
            std::cout << "gnuplot not installed: no plots\n";
            return;
        }
        std::map<std::string, std::vector<const Row*>> series;
        for (const auto& r : rows_)
            if (!r.walls.empty()) series[r.config + " " + r.volume].push_back(&r);
        if (series.empty()) {
            std::cout << "no successful run: no plots\n";
            return;
        }
        std::vector<std::pair<std::string, std::string>> files; // title, .dat
        int n = 0;
        for (const auto& [name, rs] : series) {
            const std::string dat = (out_ / ("scale_series" + std::to_string(n++) + ".dat")).string();
            std::ofstream f(dat);
            for (const Row* r : rs)
                f << r->ranks << " " << r->wall() << " " << r->vps() / 1e6 << " " << r->peak_rank << " " << r->total
                  << "\n";
            files.emplace_back(name, dat);
        }
        auto style = [](const std::string& title) {
            if (title.rfind("vtkFlyingEdges3D", 0) == 0) return std::string("with points pt 7 ps 2");
            if (title.rfind("isoscope-mpi", 0) == 0) return std::string("with linespoints pt 5 lw 2");
            return std::string("with points pt 9 ps 2"); // a single process, no mpirun
        };
        std::ofstream gp(out_ / "scale_bench.gp");
        gp << "set terminal pngcairo size 1200,500 noenhanced\nset key outside bottom center horizontal font ',9'\n"
           << "set grid\nset xlabel 'ranks (mpirun -np; single process at 1)'\nset xtics 1\nset xrange [0.5:*]\n";
        const bool budget = a_.isoscope_args.find("{memory}") != std::string::npos;
        const std::string budget_note = budget ? "" : " (not passed: in-memory command)";
        gp << "set output '" << (out_ / "scale_time.png").string()
           << "'\nset multiplot layout 1,2 title 'isoscope mesh: "
           << (budget ? "out of core (budget " + std::to_string(a_.memory) + " MiB)" : "in memory") << " and MPI, iso "
           << a_.iso << "; vtkFlyingEdges3D holds the whole volume'\n";
        gp << "set title 'wall time (lower is better)'\nset ylabel 's'\nset yrange [0:*]\nplot ";
        for (std::size_t i = 0; i < files.size(); ++i)
            gp << (i ? ", " : "") << "'" << files[i].second << "' using 1:2 " << style(files[i].first) << " title '"
               << files[i].first << "'";
        gp << "\nset title 'throughput (higher is better)'\nset ylabel 'Mvoxel/s'\nplot ";
        for (std::size_t i = 0; i < files.size(); ++i)
            gp << (i ? ", " : "") << "'" << files[i].second << "' using 1:3 " << style(files[i].first) << " title '"
               << files[i].first << "'";
        gp << "\nunset multiplot\n";
        gp << "set output '" << (out_ / "scale_memory.png").string()
           << "'\nset terminal pngcairo size 900,550 noenhanced\n"
           << "set title 'peak resident memory per rank (solid) and total (dashed) vs the budget'\nset ylabel 'MiB'\n"
           << "set yrange [0:*]\nplot " << a_.memory << " with lines lc 'black' lw 2 title 'budget " << a_.memory
           << " MiB" << budget_note << "', " << a_.memory + a_.slack << " with lines lc 'black' dt 2 title 'budget + "
           << a_.slack << " MiB'";
        for (std::size_t i = 0; i < files.size(); ++i)
            gp << ", '" << files[i].second << "' using 1:4 " << style(files[i].first) << " lc " << i + 1 << " title '"
               << files[i].first << " per rank', '' using 1:5 with linespoints dt 2 lc " << i + 1 << " title 'total'";
        gp << "\n";
        gp.close();
        if (std::system(("gnuplot '" + (out_ / "scale_bench.gp").string() + "'").c_str()) != 0)
            std::cerr << "gnuplot failed\n";
        else
            std::cout << "wrote " << (out_ / "scale_time.png").string() << " and scale_memory.png\n";
    }

    Args a_;
    fs::path out_;
    std::vector<Row> rows_;
    std::vector<std::string> gen_notes_;
};

} // namespace

int main(int argc, char** argv) {
    Args a;
    for (int i = 1; i < argc; ++i) {
        const std::string s = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) usage(s + " needs a value");
            return argv[++i];
        };
        auto number = [&](const std::string& v) {
            try {
                std::size_t pos = 0;
                const double d = std::stod(v, &pos);
                if (pos != v.size()) throw 0;
                return d;
            } catch (...) {
                usage(s + ": '" + v + "' is not a number");
            }
        };
        if (s == "--quick")
            a.quick = true;
        else if (s == "--out")
            a.out = next();
        else if (s == "--data")
            a.data = next();
        else if (s == "--sizes")
            for (const auto& w : split(next(), ',')) a.sizes.push_back(parse_size(w));
        else if (s == "--ranks")
            for (const auto& w : split(next(), ',')) a.ranks.push_back(int(number(w)));
        else if (s == "--reps")
            a.reps = int(number(next()));
        else if (s == "--reps-large")
            a.reps_large = int(number(next()));
        else if (s == "--warmup")
            a.warmup = int(number(next()));
        else if (s == "--iso")
            a.iso = number(next());
        else if (s == "--memory")
            a.memory = int(number(next()));
        else if (s == "--slack")
            a.slack = int(number(next()));
        else if (s == "--threads")
            a.threads = int(number(next()));
        else if (s == "--isoscope")
            a.isoscope = next();
        else if (s == "--mpirun")
            a.mpirun = next();
        else if (s == "--isoscope-args")
            a.isoscope_args = next();
        else if (s == "--mpirun-args")
            a.mpirun_args = next();
        else if (s == "--isoscope-mpi-args")
            a.isoscope_mpi_args = next();
        else if (s == "--no-single")
            a.single = false;
        else if (s == "--no-mpi")
            a.mpi = false;
        else if (s == "--no-fe")
            a.fe = false;
        else if (s == "--fe-max-gib")
            a.fe_max_gib = number(next());
        else if (s == "--cache")
            a.cache = next();
        else if (s == "--timeout")
            a.timeout = number(next());
        else if (s == "--keep-output")
            a.keep_output = true;
        else if (s == "--generate-only")
            a.generate_only = true;
        else if (s == "--one")
            a.one = next();
        else if (s == "--in")
            a.in = next();
        else
            usage("unknown option " + s);
    }
    if (a.cache != "warm" && a.cache != "cold") usage("--cache must be warm or cold");
    if (a.threads < 1 || a.memory < 1 || a.slack < 0 || a.warmup < 0 || a.reps_large < 1)
        usage("--threads, --memory and --reps-large must be >= 1, --slack and --warmup >= 0");
    for (int n : a.ranks)
        if (n < 1) usage("--ranks must be >= 1");
    try {
        if (a.one == "fe") return run_fe(a);
        if (!a.one.empty()) usage("unknown child mode " + a.one);
        // Quick: 256^3 (32 MiB), 1 and 2 ranks, one measured run: checks the harness in under a minute.
        if (a.sizes.empty())
            a.sizes = a.quick ? std::vector<std::array<std::int64_t, 3>>{{256, 256, 256}}
                              : std::vector<std::array<std::int64_t, 3>>{{1024, 1024, 1024}, {2048, 2048, 1024}};
        if (a.ranks.empty()) a.ranks = a.quick ? std::vector<int>{1, 2} : std::vector<int>{1, 2, 4};
        if (a.reps < 0) a.reps = a.quick ? 1 : 3;
        if (a.reps < 1) usage("--reps must be >= 1");
        struct sigaction sa {};
        sa.sa_handler = on_sigint;
        ::sigaction(SIGINT, &sa, nullptr);
        ::sigaction(SIGTERM, &sa, nullptr);
        return Bench(a).run();
    } catch (const std::exception& e) {
        std::cerr << "\nscale_bench: " << e.what() << "\n";
        return 1;
    }
}
