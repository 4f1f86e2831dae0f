// The huge-page advice (huge_pages.h) must change no value: buffers advised before, during and after
// growth hold what was written, and advice on small, unaligned or null ranges is harmless.
#include "libmrtile/huge_pages.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <vector>

namespace {

TEST(HugePages, advised_vectors_keep_their_contents_across_growth)
{
    // From one element to 16 MiB by push_back: the reallocations cross kHugePageMinBytes.
    std::vector<std::uint64_t, mrt::HugePageAllocator<std::uint64_t>> v;
    const std::size_t n = std::size_t{2} << 20;
    for (std::size_t i = 0; i < n; ++i)
        v.push_back(i * 2654435761u);
    ASSERT_EQ(v.size(), n);
    for (std::size_t i = 0; i < n; i += 4099)
        EXPECT_EQ(v[i], i * 2654435761u);
    EXPECT_EQ(v.back(), (n - 1) * 2654435761u);
    // Copies and moves between such vectors and from a plain one.
    auto copy = v;
    EXPECT_EQ(copy, v);
    std::vector<std::uint64_t> plain(v.begin(), v.end());
    EXPECT_TRUE(std::equal(plain.begin(), plain.end(), copy.begin()));
}

TEST(HugePages, advice_on_any_range_is_harmless)
{
    mrt::advise_huge_pages(nullptr, std::size_t{64} << 20);
    std::vector<char> small(100, 'a');
    mrt::advise_huge_pages(small.data(), small.size());
    EXPECT_EQ(std::count(small.begin(), small.end(), 'a'), 100);
    // A large buffer advised at an odd offset, written after the advice.
    std::vector<std::uint32_t> big;
    big.reserve(std::size_t{3} << 20);
    mrt::advise_huge_pages(reinterpret_cast<const char*>(big.data()) + 12345, big.capacity() * sizeof(std::uint32_t) - 12345);
    big.resize(big.capacity());
    std::iota(big.begin(), big.end(), 0u);
    EXPECT_EQ(big[123456], 123456u);
    EXPECT_EQ(big.back(), big.size() - 1);
}

} // namespace
