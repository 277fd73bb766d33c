#include "apps/loom/PassDocs.h"

#include <fmt/format.h>

#include <fstream>
#include <iostream>
#include <sstream>

#include "core/util/Error.h"
#include "core/util/AtomicFile.h"

namespace loom {

using nlohmann::json;

namespace {

std::string cell(std::string s) {
    std::string out;
    for (char c : s) {
        if (c == '|')
            out += "\\|";
        else if (c == '\n')
            out += ' ';
        else
            out += c;
    }
    return out;
}

std::string number(double v) {
    std::string s = fmt::format("{}", v);
    return s;
}

std::string valueText(const json& v) {
    if (v.is_string()) return v.get<std::string>().empty() ? "\"\"" : v.get<std::string>();
    if (v.is_number_float()) return number(v.get<double>());
    if (v.is_array()) {
        std::string s = "(";
        for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + valueText(v[i]);
        return s + ")";
    }
    return v.dump();
}

std::string typeText(const json& p) {
    std::string t = p["type"];
    if (t == "enum") {
        std::string s = "enum ";
        for (size_t i = 0; i < p["choices"].size(); ++i)
            s += (i ? ", " : "") + p["choices"][i].get<std::string>();
        return s;
    }
    bool lo = p.contains("min"), hi = p.contains("max");
    if (lo && hi) return fmt::format("{} [{}, {}]", t, number(p["min"]), number(p["max"]));
    if (lo) return fmt::format("{} ≥ {}", t, number(p["min"]));
    if (hi) return fmt::format("{} ≤ {}", t, number(p["max"]));
    return t;
}

std::string sizeText(const json& port) {
    if (!port.contains("size")) return port.value("format", "");
    const json& s = port["size"];
    if (s.contains("bytes")) return fmt::format("{} B", s["bytes"].get<uint64_t>());
    uint64_t extra = s.value("extraBytes", uint64_t(0)), per = s["bytesPerPixel"];
    return extra ? fmt::format("{} B + {} B / pixel", extra, per)
                 : fmt::format("{} B / pixel", per);
}

}  // namespace

std::string passTablesMarkdown(const json& pass) {
    std::ostringstream o;
    o << "| port | kind | format / size | doc |\n| --- | --- | --- | --- |\n";
    for (const char* dir : {"inputs", "outputs"})
        for (auto& p : pass[dir]) {
            std::string kind = p["kind"];
            if (p.value("previousFrame", false)) kind += ", **previous frame**";
            if (p.value("optional", false)) kind += ", optional";
            if (p.contains("inPlaceOf"))
                kind += ", in place of `" + p["inPlaceOf"].get<std::string>() + "`";
            o << "| " << (dir[0] == 'i' ? "in" : "out") << " `" << p["name"].get<std::string>()
              << "` | " << kind << " | " << cell(sizeText(p)) << " | "
              << cell(p["doc"].get<std::string>()) << " |\n";
        }
    if (pass.contains("scratch"))
        for (auto& p : pass["scratch"])
            o << "| scratch `" << p["name"].get<std::string>() << "` | "
              << p["kind"].get<std::string>() << " | " << cell(sizeText(p)) << " | "
              << cell(p["doc"].get<std::string>()) << " |\n";
    if (!pass["params"].empty()) {
        o << "\n| parameter | type | default | doc |\n| --- | --- | --- | --- |\n";
        for (auto& p : pass["params"])
            o << "| `" << p["name"].get<std::string>() << "` | " << cell(typeText(p)) << " | "
              << cell(valueText(p["default"])) << " | " << cell(p["doc"].get<std::string>())
              << " |\n";
    }
    if (!pass["persistent"].empty()) {
        o << "\n| persistent | doc |\n| --- | --- |\n";
        for (auto& p : pass["persistent"])
            o << "| `" << p["name"].get<std::string>() << "` | "
              << cell(p["doc"].get<std::string>()) << " |\n";
    }
    return o.str();
}

int updatePassDocs(const json& passes, const std::vector<std::string>& files, bool check) {
    const std::string open = "<!-- loom passes ", close = "<!-- /loom passes -->";
    int changed = 0;
    for (const auto& file : files) {
        std::ifstream in(file, std::ios::binary);
        if (!in) throw UserError(fmt::format("{}: cannot read", file));
        std::stringstream ss;
        ss << in.rdbuf();
        std::string text = ss.str(), out;
        std::istringstream lines(text);
        std::string line;
        int lineNo = 0, fileChanged = 0;
        while (std::getline(lines, line)) {
            ++lineNo;
            out.append(line).push_back('\n');
            if (line.rfind(open, 0) != 0) continue;
            std::string type = line.substr(open.size());
            type = type.substr(0, type.find(' '));
            const json* pass = nullptr;
            for (auto& p : passes)
                if (p["type"] == type) pass = &p;
            if (!pass)
                throw UserError(fmt::format("{}:{}: unknown pass type '{}'", file, lineNo, type));
            std::string old;
            int start = lineNo;
            bool closed = false;
            while (std::getline(lines, line)) {
                ++lineNo;
                if (line == close) {
                    closed = true;
                    break;
                }
                old.append(line).push_back('\n');
            }
            if (!closed)
                throw UserError(fmt::format("{}:{}: '{}' has no closing '{}'", file, start,
                                            open + type + " -->", close));
            std::string tables = passTablesMarkdown(*pass);
            if (tables != old) {
                ++fileChanged;
                if (check)
                    std::cerr << fmt::format(
                        "{}:{}: the {} tables differ from its reflect(); run loom passes "
                        "--update-docs {}\n",
                        file, start, type, file);
            }
            out.append(tables).append(close).push_back('\n');
        }
        if (fileChanged && !check) {
            writeTextFileAtomic(file, "README", out);
        }
        changed += fileChanged;
    }
    return changed;
}

}  // namespace loom
