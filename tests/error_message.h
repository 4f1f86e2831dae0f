#pragma once
// The message of the exception a call throws, for tests that check the one line a user sees.
#include "libmrtile/errors.h"

#include <string>

namespace mrt::testing {

//! The what() of the E that f throws; "" if it throws nothing (another exception type propagates).
template <typename E = InvalidInput, typename F>
std::string error_message(F&& f)
{
    try {
        f();
    } catch (const E& e) {
        return e.what();
    }
    return {};
}

} // namespace mrt::testing
