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
#include <unistd.h>
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

//! Runs the gltf-transform CLI's `inspect` (glTF-Transform's own reader, with its Draco decoder) on
//! one file; returns its Markdown report (throws if it cannot read the file).
inline std::string gltf_transform_inspect(const std::string& file)
{
    const std::filesystem::path cli = npm_dir() / "node_modules" / ".bin" / "gltf-transform";
    if (!std::filesystem::exists(cli))
        throw std::runtime_error(cli.string() + " is missing: run `bash tools/setup.sh` (npm ci in tests/npm)");
    return run_command(shell_quote(cli.string()) + " inspect " + shell_quote(file) + " --format md");
}

//! The cells of the first Markdown table row of `report` that follows the header containing `column`
//! and starts with `first_cell` (e.g. "0").
inline std::vector<std::string> markdown_row(const std::string& report, const std::string& column,
                                             const std::string& first_cell)
{
    std::size_t pos = report.find("| " + column + " ");
    if (pos == std::string::npos)
        pos = report.find(" " + column + " |");
    while (pos != std::string::npos) {
        pos = report.find('\n', pos);
        if (pos == std::string::npos)
            break;
        const std::size_t end = report.find('\n', pos + 1);
        const std::string line = report.substr(pos + 1, end == std::string::npos ? std::string::npos : end - pos - 1);
        if (line.empty() || line[0] != '|')
            break;
        std::vector<std::string> cells;
        std::size_t start = 1;
        for (std::size_t bar = line.find('|', start); bar != std::string::npos; bar = line.find('|', start)) {
            std::string cell = line.substr(start, bar - start);
            cell.erase(0, cell.find_first_not_of(' '));
            cell.erase(cell.find_last_not_of(' ') + 1);
            cells.push_back(cell);
            start = bar + 1;
        }
        if (!cells.empty() && cells[0] == first_cell)
            return cells;
        pos = end;
    }
    return {};
}

} // namespace mrt::testing
