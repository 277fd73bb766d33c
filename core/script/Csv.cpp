#include "core/script/Csv.h"

#include <algorithm>
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

CsvTable readCsv(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw UserError(path + ": cannot open CSV file");
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();

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
    auto writeRecord = [&](const std::vector<std::string>& rec) {
        for (size_t i = 0; i < rec.size(); ++i) text += (i ? "," : "") + csvQuote(rec[i]);
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
    for (auto& path : paths) {
        CsvTable t = readCsv(path);
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
