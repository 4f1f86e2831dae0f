#pragma once
// A fresh, empty scratch directory per test, inside the build tree: ctest runs each test case in its
// own process in parallel, so cases must not share files, and tests never write outside the build dir.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace mrt::testing {

//! <build>/test_tmp/<group>/<Suite>.<case>, emptied and created.
inline std::filesystem::path fresh_test_dir(const std::string& group)
{
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const std::filesystem::path dir = std::filesystem::path(MRTILE_BINARY_DIR) / "test_tmp" / group /
                                      (std::string(info->test_suite_name()) + "." + info->name());
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

} // namespace mrt::testing
