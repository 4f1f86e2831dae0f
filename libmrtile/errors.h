#pragma once
//! \file errors.h
//! \brief The exceptions the library throws. Messages are one line a user can act on: they name the
//! file (for I/O) or the parameter (for caller mistakes) and the cause.

#include <stdexcept>
#include <string>

namespace mrt {

//! A caller mistake or unusable data: bad parameter, empty or non-finite cloud, malformed file content.
class InvalidInput : public std::runtime_error
{
public:
    using std::runtime_error::runtime_error;
};

//! A file could not be opened, read, written or renamed, or is truncated or corrupted.
class IoError : public std::runtime_error
{
public:
    using std::runtime_error::runtime_error;
};

} // namespace mrt
