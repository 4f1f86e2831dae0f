// Fuzz target for the model file (libmrtile/model_file.h): forged or corrupted .mrt bytes must be refused
// with IoError or InvalidInput (the checksum is recomputed over the fuzzed body first, so the fuzzer
// reaches the structural checks behind it), never a crash, a hang or an allocation of what a forged size
// declares.
#include "libmrtile/errors.h"
#include "libmrtile/model_file.h"

#include <zlib.h>

#include <cstdint>
#include <string>

namespace {

// The trailer is the CRC-32 of everything before it (little-endian) and "MEND": rewrite it.
std::string with_valid_checksum(std::string bytes)
{
    if (bytes.size() < 8)
        return bytes;
    const std::size_t end = bytes.size() - 8;
    const uLong value = crc32(crc32(0L, Z_NULL, 0), reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(end));
    for (int k = 0; k < 4; ++k)
        bytes[end + static_cast<std::size_t>(k)] = static_cast<char>((value >> (8 * k)) & 0xFF);
    bytes.replace(end + 4, 4, "MEND");
    return bytes;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    for (const std::string& candidate : {bytes, with_valid_checksum(bytes)}) {
        try {
            const mrt::Model m = mrt::deserialize_model_with_levels(candidate, "fuzz.mrt");
            (void)m;
        } catch (const mrt::InvalidInput&) {
        } catch (const mrt::IoError&) {
        }
    }
    return 0;
}
