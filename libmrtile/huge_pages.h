#pragma once
//! \file huge_pages.h
//! \brief Internal: asks the kernel to back large working buffers with transparent huge pages.
//! \details The hierarchy build writes every point's record about once per tree level into fresh
//! buffers (a split moves a cluster's members into two new ones), so most of its memory traffic lands
//! on pages touched for the first time. On virtual machines a 4 KiB page fault costs several
//! microseconds: the 1M-point build took 69,000 faults, about a fifth of its CPU time. Advised
//! buffers fault once per 2 MiB instead (8,600 faults, −20% CPU, peak memory +4%). The advice changes
//! no value anywhere; where the kernel lacks it or has THP off, it does nothing.

#include <cstddef>
#include <cstdint>
#include <memory>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace mrt {

//! Buffers smaller than this are left alone: a huge page needs an aligned 2 MiB inside the buffer.
inline constexpr std::size_t kHugePageMinBytes = std::size_t{4} << 20;

//! Advises huge pages for the 2 MiB-aligned interior of [p, p + bytes), before it is first written.
inline void advise_huge_pages(const void* p, std::size_t bytes)
{
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
    if (p == nullptr || bytes < kHugePageMinBytes)
        return;
    const auto begin = reinterpret_cast<std::uintptr_t>(p);
    const std::uintptr_t first = (begin + kHuge - 1) & ~(kHuge - 1);
    const std::uintptr_t last = (begin + bytes) & ~(kHuge - 1);
    if (last > first)
        (void)::madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE); // advice only: failure is harmless
#else
    (void)p;
    (void)bytes;
#endif
}

//! Reserves room for `n` elements in an empty vector and advises huge pages for it, before it is filled.
template <class Vector>
void reserve_on_huge_pages(Vector& v, std::size_t n)
{
    v.reserve(n);
    advise_huge_pages(v.data(), n * sizeof(typename Vector::value_type));
}

//! std::allocator that advises huge pages for every large block it hands out (the build's per-cluster
//! member lists: see the file comment). Mapping large blocks on their own in whole huge pages was
//! tried: more 4 KiB faults (glibc then kept its mmap threshold low), no faster.
template <class T>
struct HugePageAllocator
{
    using value_type = T;
    HugePageAllocator() = default;
    template <class U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept
    {
    }
    T* allocate(std::size_t n)
    {
        T* p = std::allocator<T>().allocate(n);
        advise_huge_pages(p, n * sizeof(T));
        return p;
    }
    void deallocate(T* p, std::size_t n) noexcept { std::allocator<T>().deallocate(p, n); }
    template <class U>
    bool operator==(const HugePageAllocator<U>&) const noexcept
    {
        return true;
    }
    template <class U>
    bool operator!=(const HugePageAllocator<U>&) const noexcept
    {
        return false;
    }
};

} // namespace mrt
