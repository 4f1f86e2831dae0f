#pragma once
// Markdown tables for tools/bench: every benchmark fills a Table, and one printer writes them all,
// so the output can be pasted into the README as it is.

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace mrt::bench {

enum class Align { Left, Right };

struct Column
{
    std::string name;
    Align align = Align::Right;
};

struct Table
{
    std::string title;                          // printed as a "###" heading
    std::vector<Column> columns;
    std::vector<std::vector<std::string>> rows; // one string per column
    std::vector<std::string> notes;             // printed under the table as a bullet list
};

// Writes the table as GitHub markdown, columns padded so the raw text lines up too.
void print_markdown(const Table& table, std::ostream& out);

// Number formatting shared by the tables.
std::string fixed(double value, int decimals);
std::string with_commas(std::uint64_t value);        // 1234567 -> "1,234,567"
std::string short_count(std::uint64_t value);        // 100000 -> "100k", 4000000 -> "4M"
std::string verdict(bool pass);                      // "PASS" / "FAIL"

} // namespace mrt::bench
