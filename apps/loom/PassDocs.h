#pragma once
// Markdown tables of a pass type's ports, parameters and persistent resources, generated from
// the same JSON as `loom passes --json` (so READMEs cannot drift from reflect()).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace loom {

// The tables of one entry of `loom passes --json`.
std::string passTablesMarkdown(const nlohmann::json& pass);

// Rewrites (or with check=true compares) every block
//   <!-- loom passes TYPE -->
//   ...
//   <!-- /loom passes -->
// in each file with TYPE's tables. Returns the number of blocks that differed (check) or were
// rewritten; throws UserError naming file and line for an unknown TYPE or an unclosed block.
int updatePassDocs(const nlohmann::json& passes, const std::vector<std::string>& files, bool check);

}  // namespace loom
