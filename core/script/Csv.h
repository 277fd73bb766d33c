#pragma once
// CSV files written by scripts (loom.write_csv) and merged across shards (loom merge).
// RFC 4180 quoting; '\n' line ends; fields are kept as text so a merge reproduces bytes.
#include <string>
#include <vector>

namespace loom::script {

struct CsvTable {
    std::vector<std::string> header;
    std::vector<std::vector<std::string>> rows;
};

// An empty file is a table without header or rows. Throws UserError naming file and line.
CsvTable readCsv(const std::string& path);
// Creates parent directories. A table without header writes an empty file.
void writeCsv(const std::string& path, const CsvTable& table);
std::string csvQuote(const std::string& field);
// Concatenates tables with identical headers (empty files are skipped); when there is an
// `index` column, rows are sorted by it (numerically, stable). Throws UserError naming the
// file whose header differs.
CsvTable mergeCsv(const std::vector<std::string>& paths);

}  // namespace loom::script
