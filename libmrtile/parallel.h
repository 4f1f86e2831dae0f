#pragma once
//! \file parallel.h
//! \brief A minimal worker pool for independent jobs whose results the caller combines in a fixed
//! order, so that the output never depends on the number of threads.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace mrt {

//! The number of threads a `threads = 0` option means: one per hardware thread unless a program set a
//! bound with set_default_threads (the CLI's --threads), so that one setting reaches every stage,
//! including those a caller cannot pass options to (the quality measurements). Results never depend on it.
inline std::atomic<std::size_t>& default_threads_setting()
{
    static std::atomic<std::size_t> setting{0};
    return setting;
}

//! Sets what `threads = 0` means from now on (0 = one per hardware thread again).
inline void set_default_threads(std::size_t threads) { default_threads_setting() = threads; }

//! \brief Calls work(0) ... work(count - 1), each exactly once, on up to `threads` threads (0 = the
//! default: set_default_threads, else one per hardware thread), the calling thread included; jobs are
//! handed out in index order as threads free up.
//! \details The first exception a job throws is rethrown once all threads have ended (the other jobs
//! still run). `work` must be safe to call concurrently for different indices.
template <typename Work>
void run_parallel(std::size_t count, std::size_t threads, const Work& work)
{
    const std::size_t fallback = default_threads_setting() > 0 ? default_threads_setting().load()
                                                               : std::max(1u, std::thread::hardware_concurrency());
    const std::size_t workers = std::min(count, threads > 0 ? threads : fallback);
    std::atomic<std::size_t> next{0};
    std::exception_ptr failure;
    std::mutex failure_mutex;
    auto worker = [&] {
        for (std::size_t k = next++; k < count; k = next++) {
            try {
                work(k);
            } catch (...) {
                const std::lock_guard<std::mutex> lock(failure_mutex);
                if (!failure)
                    failure = std::current_exception();
            }
        }
    };
    std::vector<std::thread> pool;
    // A thread the system cannot start (threads = 10000 past its limits) leaves the jobs to the threads
    // that did start: a std::system_error here used to unwind past the joinable threads of `pool`,
    // which is std::terminate. The result does not depend on the number of threads.
    for (std::size_t t = 1; t < workers; ++t) {
        try {
            pool.emplace_back(worker);
        } catch (const std::system_error&) {
            break;
        }
    }
    worker();
    for (std::thread& t : pool)
        t.join();
    if (failure)
        std::rethrow_exception(failure);
}

//! \brief Calls work(begin, end) for the ranges [0, block), [block, 2 block), ... that cover
//! [0, count) (the last one shorter), as run_parallel's jobs: for loops over many small items, whose
//! ranges are the jobs. A range's items are one job's, in order, so per-range state (a search hint)
//! may live in `work`. `block` must be at least 1.
template <typename Work>
void run_parallel_ranges(std::size_t count, std::size_t block, std::size_t threads, const Work& work)
{
    run_parallel((count + block - 1) / block, threads,
                 [&](std::size_t r) { work(r * block, std::min(count, (r + 1) * block)); });
}

} // namespace mrt
