#include "core/script/Csv.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/util/AtomicFile.h"
#include "core/util/Error.h"
#include "core/util/Log.h"

namespace loom::script {

std::string csvQuote(const std::string& field) {
    if (field.find_first_of(",\"\r\n") == std::string::npos) return field;
    std::string out = "\"";
    for (char c : field) {
        if (c == '"') out += '"';
        out += c;
    }
    return out + "\"";
}

namespace {
constexpr const char* kSweepTag = "# loom-sweep ";

// "# loom-sweep id=ID shard=I/N" (without the newline).
SweepPart parseSweepLine(const std::string& path, const std::string& line) {
    SweepPart part;
    std::stringstream ss(line.substr(std::string(kSweepTag).size()));
    std::string word;
    bool haveId = false, haveShard = false;
    while (ss >> word) {
        if (word.rfind("id=", 0) == 0) {
            part.id = word.substr(3);
            haveId = !part.id.empty();
        } else if (word.rfind("shard=", 0) == 0) {
            unsigned i = 0, n = 0;
            char tail = 0;
            if (std::sscanf(word.c_str() + 6, "%u/%u%c", &i, &n, &tail) == 2 && n > 0 && i < n) {
                part.index = i;
                part.count = n;
                haveShard = true;
            }
        }
    }
    if (!haveId || !haveShard)
        throw UserError(path + ":1: malformed sweep line '" + line +
                        "' (expected '# loom-sweep id=ID shard=I/N')");
    return part;
}
}  // namespace

std::string csvPartPath(const std::string& path, uint32_t index) {
    std::filesystem::path p(path);
    return (p.parent_path() / (p.stem().string() + ".PART-" + std::to_string(index) + ".csv"))
        .string();
}

CsvTable readCsv(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UserError(path + ": cannot open CSV file");
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    std::optional<SweepPart> sweep;
    if (text.rfind(kSweepTag, 0) == 0) {
        size_t eol = text.find('\n');
        sweep = parseSweepLine(path, text.substr(0, eol));
        text = eol == std::string::npos ? "" : text.substr(eol + 1);
    }

    // A small RFC 4180 state machine: quoted fields may hold commas, quotes ("") and newlines.
    std::vector<std::vector<std::string>> records;
    std::vector<std::string> record;
    std::string field;
    bool quoted = false, fieldStarted = false;
    int line = 1;
    auto endField = [&] {
        record.push_back(field);
        field.clear();
        fieldStarted = false;
    };
    auto endRecord = [&] {
        endField();
        records.push_back(std::move(record));
        record.clear();
    };
    for (size_t i = 0; i < text.size(); ++i) {
        char c = text[i];
        if (quoted) {
            if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
                field += '"';
                ++i;
            } else if (c == '"') {
                quoted = false;
            } else {
                if (c == '\n') ++line;
                field += c;
            }
        } else if (c == '"' && !fieldStarted) {
            quoted = fieldStarted = true;
        } else if (c == ',') {
            endField();
        } else if (c == '\n' || c == '\r') {
            if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
            endRecord();
            ++line;
        } else {
            field += c;
            fieldStarted = true;
        }
    }
    if (quoted) throw UserError(fmt::format("{}:{}: unterminated quoted field", path, line));
    if (fieldStarted || !field.empty() || !record.empty()) endRecord();

    CsvTable table;
    table.sweep = sweep;
    if (records.empty()) return table;
    table.header = records.front();
    for (size_t r = 1; r < records.size(); ++r) {
        if (records[r].size() == 1 && records[r][0].empty()) continue;  // blank line
        if (records[r].size() != table.header.size())
            throw UserError(fmt::format("{}: record {} has {} fields but the header has {}", path,
                                        r + 1, records[r].size(), table.header.size()));
        table.rows.push_back(std::move(records[r]));
    }
    return table;
}

void writeCsv(const std::string& path, const CsvTable& table) {
    std::string text;
    if (table.sweep)
        text = fmt::format("{}id={} shard={}/{}\n", kSweepTag, table.sweep->id, table.sweep->index,
                           table.sweep->count);
    auto writeRecord = [&](const std::vector<std::string>& rec) {
        for (size_t i = 0; i < rec.size(); ++i) {
            if (i) text += ',';  // not (i ? "," : "") + ...: GCC 12's -Wrestrict false positive
            text += csvQuote(rec[i]);
        }
        text += "\n";
    };
    if (!table.header.empty()) {
        writeRecord(table.header);
        for (auto& row : table.rows) writeRecord(row);
    }
    writeTextFileAtomic(path, "CSV file", text);
}

CsvTable mergeCsv(const std::vector<std::string>& paths) {
    CsvTable merged;
    std::string headerFrom;
    std::optional<SweepPart> sweep;
    std::string sweepFrom, plainFrom;
    std::vector<std::string> shardFrom;
    for (auto& path : paths) {
        CsvTable t = readCsv(path);
        if (t.sweep) {
            if (!sweep) {
                sweep = t.sweep;
                sweepFrom = path;
                shardFrom.assign(sweep->count, "");
            } else if (t.sweep->id != sweep->id || t.sweep->count != sweep->count) {
                throw UserError(fmt::format(
                    "{}: part of sweep {} ({} shards), but {} is part of sweep {} ({} shards): "
                    "parts of different sweeps do not merge",
                    path, t.sweep->id, t.sweep->count, sweepFrom, sweep->id, sweep->count));
            }
            std::string& seen = shardFrom[t.sweep->index];
            if (!seen.empty())
                throw UserError(fmt::format("{}: shard {}/{} is also in {}", path, t.sweep->index,
                                            t.sweep->count, seen));
            seen = path;
        } else {
            plainFrom = path;
        }
        if (sweep && !plainFrom.empty())
            throw UserError(fmt::format("{}: not a part of a sweep, but {} is (sweep {})",
                                        plainFrom, sweepFrom, sweep->id));
        if (t.header.empty()) continue;  // a shard that owned no values
        if (merged.header.empty()) {
            merged.header = t.header;
            headerFrom = path;
        } else if (t.header != merged.header) {
            auto join = [](const std::vector<std::string>& v) {
                std::string s;
                for (auto& x : v) s += (s.empty() ? "" : ",") + x;
                return s;
            };
            throw UserError(fmt::format("{}: header '{}' differs from '{}' in {}", path,
                                        join(t.header), join(merged.header), headerFrom));
        }
        for (auto& row : t.rows) merged.rows.push_back(std::move(row));
    }
    if (sweep) {
        std::string missing;
        for (uint32_t i = 0; i < sweep->count; ++i)
            if (shardFrom[i].empty()) missing += (missing.empty() ? "" : ", ") + std::to_string(i);
        if (!missing.empty())
            throw UserError(fmt::format("sweep {}: shard(s) {} of {} missing (no part file given)",
                                        sweep->id, missing, sweep->count));
    }
    auto it = std::find(merged.header.begin(), merged.header.end(), "index");
    if (it != merged.header.end()) {
        size_t col = size_t(it - merged.header.begin());
        auto key = [&](const std::vector<std::string>& row) {
            char* end = nullptr;
            double v = std::strtod(row[col].c_str(), &end);
            if (row[col].empty() || *end != '\0')
                throw UserError("merge: 'index' value '" + row[col] + "' is not a number");
            return v;
        };
        for (auto& row : merged.rows) key(row);  // validate before sorting
        std::stable_sort(merged.rows.begin(), merged.rows.end(),
                         [&](const auto& a, const auto& b) { return key(a) < key(b); });
    }
    return merged;
}

}  // namespace loom::script
