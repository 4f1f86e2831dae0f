#pragma once
// Measuring for tools/bench: wall and CPU time of a call, the process's resident memory and its peak,
// and running a case in a forked child so that each case's peak memory is its own.

#include <cstddef>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace mrt::bench {

struct Timing
{
    double wall = 0.0; // seconds, steady clock
    double cpu = 0.0;  // seconds of CPU used by the whole process (user + system)
};

Timing time_call(const std::function<void()>& work);

// Runs `work` until it has run at least `min_runs` times and for at least `min_seconds` in total
// (but at most `max_runs` times) and returns the fastest run (by CPU time) — for cases too short to
// time once.
Timing time_fastest(const std::function<void()>& work, int min_runs, int max_runs, double min_seconds);

// Resident set size now and its peak since the process started or since reset_peak_rss(), in bytes
// (VmRSS / VmHWM of /proc/self/status).
std::size_t resident_bytes();
std::size_t peak_resident_bytes();
// Resets the peak to the current resident size (Linux ≥ 4.0: "5" > /proc/self/clear_refs). Returns
// false if the kernel refused; the peak then still counts everything since the process started.
bool reset_peak_rss();

// Runs `work` in a forked child and returns the bytes it returned. The child's memory is its own, so
// its peak resident size is that of the case alone, and whatever it allocates is gone afterwards.
// \throw std::runtime_error with the child's exception message, or if the child died (signal, OOM).
std::string run_in_child(const std::function<std::string()>& work);

// Typed form of run_in_child() for a plain struct of numbers.
template <class Result>
Result run_in_child(const std::function<Result()>& work)
{
    static_assert(std::is_trivially_copyable_v<Result>, "results cross a pipe as raw bytes");
    const std::string bytes = run_in_child(std::function<std::string()>([&work] {
        const Result r = work();
        return std::string(reinterpret_cast<const char*>(&r), sizeof r);
    }));
    Result r{};
    if (bytes.size() != sizeof r)
        throw std::runtime_error("benchmark child returned " + std::to_string(bytes.size()) + " bytes, expected " +
                                 std::to_string(sizeof r));
    std::memcpy(&r, bytes.data(), sizeof r);
    return r;
}

// "load average 1.23 1.10 0.98" from /proc/loadavg (the machine may be shared while benchmarking).
std::string load_average();

} // namespace mrt::bench
