// Tests of parallel.h: every job runs exactly once whatever the thread count, and a job's exception
// reaches the caller after the others have run.
#include "libmrtile/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
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

} // namespace
} // namespace mrt
