// Fuzz target for the CRS texts (libmrtile/georef.h) that a .prj given to --crs or a LAS file's WKT record
// holds: parse_crs must give a CRS or an InvalidInput on one line of bounded length (a megabyte of a name
// was quoted whole, QA round qa-fuzz), and crs_differ and crs_label never throw nor hang, whatever the
// bytes. A byte 0x01 splits the input into the two texts compared (else the second is EPSG:32633).
#include "libmrtile/errors.h"
#include "libmrtile/georef.h"

#include <cstdint>
#include <cstdlib>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    const std::size_t split = bytes.find('\x01');
    const std::string a = bytes.substr(0, split);
    const std::string b = split == std::string::npos ? std::string("EPSG:32633") : bytes.substr(split + 1);
    try {
        const mrt::ProjectedCrs crs = mrt::parse_crs(a);
        if (crs.name.size() > 80)
            std::abort(); // a name for messages
    } catch (const mrt::InvalidInput& e) {
        const std::string message = e.what();
        if (message.find('\n') != std::string::npos || message.size() > 1000)
            std::abort(); // errors are one readable line
    }
    (void)mrt::crs_differ(a, b);
    (void)mrt::crs_differ(b, a);
    if (mrt::crs_label(a).size() > 100 || mrt::crs_label(b).size() > 100)
        std::abort();
    return 0;
}
