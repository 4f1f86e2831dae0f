#pragma once
// Runs the node validation scripts of tests/npm (real glTF / Draco clients) from GoogleTest tests and
// parses their JSON output. A missing node_modules is a test failure with the command to fix it, never
// a skip: the exporters are only proven by these clients.
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace mrt::testing {

inline std::filesystem::path npm_dir() { return std::filesystem::path(MRTILE_SOURCE_DIR) / "tests" / "npm"; }

inline std::string shell_quote(const std::string& s)
{
    std::string out = "'";
    for (const char c : s)
        out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

//! Runs `command` (through the shell), returns its standard output. Throws with the exit status and
//! standard error on failure.
inline std::string run_command(const std::string& command)
{
    const std::filesystem::path err = std::filesystem::temp_directory_path() /
                                      ("mrtile_node_stderr_" + std::to_string(::getpid()) + ".txt");
    FILE* pipe = ::popen((command + " 2>" + shell_quote(err.string())).c_str(), "r");
    if (pipe == nullptr)
        throw std::runtime_error("cannot run: " + command);
    std::string out;
    std::array<char, 65536> buffer;
    std::size_t n;
    while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
        out.append(buffer.data(), n);
    const int status = ::pclose(pipe);
    if (status != 0) {
        std::string message;
        if (FILE* f = std::fopen(err.c_str(), "r")) {
            while ((n = std::fread(buffer.data(), 1, buffer.size(), f)) > 0)
                message.append(buffer.data(), n);
            std::fclose(f);
        }
        std::filesystem::remove(err);
        throw std::runtime_error("command failed (status " + std::to_string(status) + "): " + command + "\n" + message);
    }
    std::filesystem::remove(err);
    return out;
}

//! Runs `node tests/npm/<script> args...` once for all arguments and parses the JSON it prints.
inline nlohmann::json run_node_script(const std::string& script, const std::vector<std::string>& args)
{
    const std::filesystem::path modules = npm_dir() / "node_modules";
    for (const char* package : {"gltf-validator", "draco3d", "@gltf-transform/cli"})
        if (!std::filesystem::exists(modules / package))
            throw std::runtime_error(
                (modules / package).string() +
                " is missing: the validators are not installed; run `bash tools/setup.sh` (npm ci in tests/npm)");
    std::string command = "node " + shell_quote((npm_dir() / script).string());
    for (const std::string& a : args)
        command += " " + shell_quote(a);
    return nlohmann::json::parse(run_command(command));
}

//! Runs the gltf-transform CLI's `validate` on one file; returns its report text (throws if it fails).
inline std::string gltf_transform_validate(const std::string& file)
{
    const std::filesystem::path cli = npm_dir() / "node_modules" / ".bin" / "gltf-transform";
    if (!std::filesystem::exists(cli))
        throw std::runtime_error(cli.string() + " is missing: run `bash tools/setup.sh`");
    return run_command(shell_quote(cli.string()) + " validate " + shell_quote(file) + " --format md");
}

} // namespace mrt::testing
