#pragma once
// CSV files written by scripts (loom.write_csv) and merged across shards (loom merge).
// RFC 4180 quoting; '\n' line ends; fields are kept as text so a merge reproduces bytes.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace loom::script {

// The shard a part file holds: its first line is "# loom-sweep id=ID shard=I/N". The id names
// the sweep (script, its text and arguments), so parts of different sweeps never merge.
struct SweepPart {
    std::string id;
    uint32_t index = 0, count = 1;
};

struct CsvTable {
    std::vector<std::string> header;
    std::vector<std::vector<std::string>> rows;
    std::optional<SweepPart> sweep;  // set for the part files of a sharded sweep
};

// An empty file is a table without header or rows. Throws UserError naming file and line.
CsvTable readCsv(const std::string& path);
// Creates parent directories. A table without header writes an empty file (a part: its
// sweep line only).
void writeCsv(const std::string& path, const CsvTable& table);
std::string csvQuote(const std::string& field);
// Where shard I of a sweep writes `path`: DIR/STEM.PART-I.csv.
std::string csvPartPath(const std::string& path, uint32_t index);
// Concatenates tables with identical headers (empty files are skipped); when there is an
// `index` column, rows are sorted by it (numerically, stable). Throws UserError naming the
// file whose header differs. Part files must all come from one sweep, and every shard
// 0..N-1 must be there exactly once; the merged table is not a part.
CsvTable mergeCsv(const std::vector<std::string>& paths);

}  // namespace loom::script
