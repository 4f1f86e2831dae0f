// Markdown output of tools/bench: padded GitHub tables, so the printed text is readable in a terminal
// and pastes into the README unchanged.
#include "tools/bench_table.h"

#include <algorithm>
#include <cassert>
#include <cstdio>

namespace mrt::bench {
namespace {

// Display width: counts UTF-8 code points, so "≤" and "×" in headers do not break the padding.
std::size_t display_width(const std::string& s)
{
    return static_cast<std::size_t>(
        std::count_if(s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

std::string pad(const std::string& s, std::size_t width, Align align)
{
    const std::string fill(width - std::min(width, display_width(s)), ' ');
    return align == Align::Left ? s + fill : fill + s;
}

} // namespace

void print_markdown(const Table& table, std::ostream& out)
{
    const std::size_t n = table.columns.size();
    std::vector<std::size_t> width(n, 3); // "---" is the shortest separator
    for (std::size_t c = 0; c < n; ++c)
        width[c] = std::max(width[c], display_width(table.columns[c].name));
    for (const auto& row : table.rows)
    {
        assert(row.size() == n);
        for (std::size_t c = 0; c < n; ++c)
            width[c] = std::max(width[c], display_width(row[c]));
    }

    out << "### " << table.title << "\n\n|";
    for (std::size_t c = 0; c < n; ++c)
        out << ' ' << pad(table.columns[c].name, width[c], table.columns[c].align) << " |";
    out << "\n|";
    for (std::size_t c = 0; c < n; ++c)
    {
        const bool right = table.columns[c].align == Align::Right;
        out << ' ' << std::string(width[c] - (right ? 1 : 0), '-') << (right ? ":" : "") << " |";
    }
    out << '\n';
    for (const auto& row : table.rows)
    {
        out << '|';
        for (std::size_t c = 0; c < n; ++c)
            out << ' ' << pad(row[c], width[c], table.columns[c].align) << " |";
        out << '\n';
    }
    if (!table.notes.empty())
        out << '\n';
    for (const auto& note : table.notes)
        out << "- " << note << '\n';
    out << '\n';
    out.flush();
}

std::string fixed(double value, int decimals)
{
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
    return buffer;
}

std::string with_commas(std::uint64_t value)
{
    std::string digits = std::to_string(value);
    for (int i = static_cast<int>(digits.size()) - 3; i > 0; i -= 3)
        digits.insert(static_cast<std::size_t>(i), ",");
    return digits;
}

std::string short_count(std::uint64_t value)
{
    if (value >= 1000000 && value % 1000000 == 0)
        return std::to_string(value / 1000000) + "M";
    if (value >= 1000 && value % 1000 == 0)
        return std::to_string(value / 1000) + "k";
    return with_commas(value);
}

std::string verdict(bool pass) { return pass ? "PASS" : "FAIL"; }

} // namespace mrt::bench
