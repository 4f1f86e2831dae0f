// Measuring for tools/bench. Peak memory comes from the kernel's own accounting (VmHWM) rather than
// from a malloc hook, so it counts everything the build touches, including allocator slack; each case
// runs in a forked child so one case's peak never hides behind an earlier, larger one.
#include "tools/bench_measure.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <limits>
#include <stdexcept>

#include <sys/wait.h>
#include <unistd.h>

namespace mrt::bench {
namespace {

double process_cpu_seconds()
{
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Reads "Key:   1234 kB" from /proc/self/status.
std::size_t status_kib(const std::string& key)
{
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.compare(0, key.size(), key) == 0 && line.size() > key.size() && line[key.size()] == ':')
            return std::stoull(line.substr(key.size() + 1));
    throw std::runtime_error("/proc/self/status has no " + key + " line");
}

void write_all(int fd, const std::string& bytes)
{
    std::size_t done = 0;
    while (done < bytes.size())
    {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return; // the parent is gone or the pipe broke: nothing useful left to do
        done += static_cast<std::size_t>(n);
    }
}

std::string read_all(int fd)
{
    std::string bytes;
    char buffer[4096];
    for (;;)
    {
        const ssize_t n = ::read(fd, buffer, sizeof buffer);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return bytes;
        bytes.append(buffer, static_cast<std::size_t>(n));
    }
}

} // namespace

Timing time_call(const std::function<void()>& work)
{
    const auto wall0 = std::chrono::steady_clock::now();
    const double cpu0 = process_cpu_seconds();
    work();
    const double cpu1 = process_cpu_seconds();
    const auto wall1 = std::chrono::steady_clock::now();
    return {std::chrono::duration<double>(wall1 - wall0).count(), cpu1 - cpu0};
}

Timing time_fastest(const std::function<void()>& work, int min_runs, int max_runs, double min_seconds)
{
    Timing best{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    double total = 0.0;
    for (int run = 0; run < max_runs && (run < min_runs || total < min_seconds); ++run)
    {
        const Timing t = time_call(work);
        total += t.wall;
        if (t.cpu < best.cpu)
            best = t;
    }
    return best;
}

std::size_t resident_bytes() { return status_kib("VmRSS") * 1024; }
std::size_t peak_resident_bytes() { return status_kib("VmHWM") * 1024; }

bool reset_peak_rss()
{
    std::ofstream out("/proc/self/clear_refs");
    out << "5";
    out.flush();
    return static_cast<bool>(out);
}

std::string run_in_child(const std::function<std::string()>& work)
{
    int fds[2];
    if (::pipe(fds) != 0)
        throw std::runtime_error("pipe() failed");
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
    const pid_t pid = ::fork();
    if (pid < 0)
    {
        ::close(fds[0]);
        ::close(fds[1]);
        throw std::runtime_error("fork() failed");
    }
    if (pid == 0)
    {
        ::close(fds[0]);
        // First byte: 'o' for a result, 'e' for an error message. _exit skips the parent's atexit
        // handlers and stream buffers, which belong to the parent.
        std::string message;
        try
        {
            message = 'o' + work();
        }
        catch (const std::exception& e)
        {
            message = std::string("e") + e.what();
        }
        catch (...)
        {
            message = "eunknown exception";
        }
        write_all(fds[1], message);
        ::close(fds[1]);
        ::_exit(0);
    }
    ::close(fds[1]);
    const std::string bytes = read_all(fds[0]);
    ::close(fds[0]);
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR)
    {
    }
    if (WIFSIGNALED(status))
        throw std::runtime_error("benchmark child killed by signal " + std::to_string(WTERMSIG(status)) +
                                 " (out of memory?)");
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || bytes.empty())
        throw std::runtime_error("benchmark child failed without a result");
    if (bytes[0] == 'e')
        throw std::runtime_error(bytes.substr(1));
    return bytes.substr(1);
}

std::string load_average()
{
    std::ifstream in("/proc/loadavg");
    double one = 0, five = 0, fifteen = 0;
    in >> one >> five >> fifteen;
    if (!in)
        return "load average unknown";
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "load average %.2f %.2f %.2f", one, five, fifteen);
    return buffer;
}

} // namespace mrt::bench
