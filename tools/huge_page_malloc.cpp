// Not a stage of the method: the command-line programs' choice of glibc's huge-page malloc (see the
// header for why and what it measured). Kept out of the library: an allocator is the host's choice.
#include "tools/huge_page_malloc.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

#if defined(__linux__)
#include <unistd.h>
#endif
#if defined(__GLIBC__)
#include <gnu/libc-version.h>
#endif

namespace mrt::tools {
namespace {

constexpr const char* kTunable = "glibc.malloc.hugetlb";

bool glibc_knows_hugetlb()
{
#if defined(__GLIBC__)
    int major = 0, minor = 0;
    if (std::sscanf(gnu_get_libc_version(), "%d.%d", &major, &minor) != 2)
        return false;
    return major > 2 || (major == 2 && minor >= 35); // the tunable came with glibc 2.35
#else
    return false;
#endif
}

// True when the kernel gives transparent huge pages only to memory that asks for them.
bool thp_mode_is_madvise()
{
    std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
    const std::string modes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    return modes.find("[madvise]") != std::string::npos;
}

bool under_valgrind()
{
    const char* preload = std::getenv("LD_PRELOAD");
    return preload != nullptr && std::strstr(preload, "vgpreload") != nullptr;
}

} // namespace

void use_huge_page_malloc(char** argv)
{
#if defined(__linux__)
    const char* old = std::getenv("GLIBC_TUNABLES");
    if ((old != nullptr && std::strstr(old, kTunable) != nullptr) || !glibc_knows_hugetlb() ||
        !thp_mode_is_madvise() || under_valgrind())
        return;
    const std::string saved = old != nullptr ? old : "";
    const std::string value = (saved.empty() ? "" : saved + ":") + kTunable + "=1";
    if (::setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0)
        return;
    ::execv("/proc/self/exe", argv);
    // Still here: the exec failed (no /proc, say). Run as we are, with the environment as it was.
    if (old != nullptr)
        ::setenv("GLIBC_TUNABLES", saved.c_str(), 1);
    else
        ::unsetenv("GLIBC_TUNABLES");
#else
    (void)argv;
#endif
}

const std::string& heap_setting()
{
    static const std::string setting = [] {
        const char* all = std::getenv("GLIBC_TUNABLES");
        const char* at = all != nullptr ? std::strstr(all, kTunable) : nullptr;
        if (at == nullptr)
            return std::string("the default malloc");
        return std::string(at, std::strcspn(at, ":")); // "glibc.malloc.hugetlb=N"
    }();
    return setting;
}

} // namespace mrt::tools
