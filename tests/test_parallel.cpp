// Tests of parallel.h: every job (and every item of ranges) runs exactly once whatever the thread count, and a job's exception
// reaches the caller after the others have run, and the default thread count can be bounded; and
// QuietOpenMesh, the one guard of global state that parallel stages share.
#include "libmrtile/mesh.h"
#include "libmrtile/parallel.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace mrt {
namespace {

TEST(Parallel, every_job_runs_once)
{
    for (std::size_t threads : {0u, 1u, 2u, 5u, 64u}) {
        std::vector<std::atomic<int>> runs(37);
        run_parallel(runs.size(), threads, [&](std::size_t k) { ++runs[k]; });
        for (std::size_t k = 0; k < runs.size(); ++k)
            EXPECT_EQ(runs[k].load(), 1) << "job " << k << " with " << threads << " threads";
    }
}

// Ranges cover [0, count) once each, in blocks of the given size (the last one shorter), whatever the
// thread count; none for no items.
TEST(Parallel, ranges_cover_every_item_once)
{
    for (std::size_t threads : {1u, 2u, 7u})
        for (std::size_t count : {0u, 1u, 63u, 64u, 65u, 1000u}) {
            std::vector<std::atomic<int>> seen(count);
            std::mutex lock;
            std::set<std::pair<std::size_t, std::size_t>> ranges;
            run_parallel_ranges(count, 64, threads, [&](std::size_t begin, std::size_t end) {
                for (std::size_t i = begin; i < end; ++i)
                    ++seen[i];
                const std::lock_guard<std::mutex> hold(lock);
                ranges.insert({begin, end});
            });
            for (std::size_t i = 0; i < count; ++i)
                EXPECT_EQ(seen[i].load(), 1) << i << " of " << count;
            EXPECT_EQ(ranges.size(), (count + 63) / 64) << count;
            for (const auto& [begin, end] : ranges) {
                EXPECT_EQ(begin % 64, 0u);
                EXPECT_EQ(end, std::min(count, begin + 64));
            }
        }
}

TEST(Parallel, no_jobs_is_fine)
{
    bool called = false;
    run_parallel(0, 3, [&](std::size_t) { called = true; });
    EXPECT_FALSE(called);
}

TEST(Parallel, an_exception_reaches_the_caller_after_all_jobs)
{
    std::atomic<int> done{0};
    EXPECT_THROW(run_parallel(20, 3,
                              [&](std::size_t k) {
                                  ++done;
                                  if (k == 7)
                                      throw std::runtime_error("job 7");
                              }),
                 std::runtime_error);
    EXPECT_EQ(done.load(), 20);
}

// set_default_threads bounds the calls that leave the thread count to the default (0), not the others.
TEST(Parallel, the_default_thread_count_can_be_bounded)
{
    auto threads_used = [](std::size_t threads) {
        std::mutex lock;
        std::set<std::thread::id> ids;
        run_parallel(64, threads, [&](std::size_t) {
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
            const std::lock_guard<std::mutex> hold(lock);
            ids.insert(std::this_thread::get_id());
        });
        return ids.size();
    };
    set_default_threads(1);
    EXPECT_EQ(threads_used(0), 1u);
    EXPECT_GT(threads_used(3), 1u); // an explicit count is kept
    set_default_threads(0);
    EXPECT_EQ(default_threads_setting().load(), 0u);
}

// Guards on different threads end in any order (tiles are cut in parallel, each under its own guard):
// OpenMesh's error stream stays silent while any guard lives, and is switched back on by the last one.
// QA round qa3: when the system could not start one of the threads asked for, std::thread's
// system_error unwound past the threads already started (std::terminate). Now the jobs run on the
// threads that started. An address-space limit makes thread stacks fail to map (root ignores a limit
// on processes); not under the sanitizers, which reserve far more address space than the limit.
#if !defined(__SANITIZE_ADDRESS__)
TEST(Parallel, threads_the_system_cannot_start_leave_the_jobs_to_the_others)
{
    EXPECT_EXIT(
        {
            rlimit limit{};
            getrlimit(RLIMIT_AS, &limit);
            limit.rlim_cur = 512ull << 20; // 512 MiB: about 60 stacks of 8 MiB at most
            setrlimit(RLIMIT_AS, &limit);
            std::atomic<std::size_t> done{0};
            run_parallel(2000, 2000, [&](std::size_t) {
                std::this_thread::sleep_for(std::chrono::milliseconds(20));
                ++done;
            });
            std::exit(done == 2000 ? 0 : 1);
        },
        testing::ExitedWithCode(0), "");
}
#endif

TEST(Parallel, quiet_openmesh_guards_overlap)
{
    ASSERT_TRUE(omerr().is_enabled());
    std::optional<QuietOpenMesh> first, second;
    first.emplace();
    second.emplace();
    first.reset(); // the first guard ends while the second still lives
    EXPECT_FALSE(omerr().is_enabled());
    second.reset();
    EXPECT_TRUE(omerr().is_enabled());
    run_parallel(64, 4, [](std::size_t) { const QuietOpenMesh quiet; });
    EXPECT_TRUE(omerr().is_enabled());
}

} // namespace
} // namespace mrt
