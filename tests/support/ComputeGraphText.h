#pragma once
// JSON text of a graph of ComputePasses whose ports are declared in their parameters (texture
// ports; shaders are never loaded by validation/compile), for GPU-free graph tests.
#include <string>
#include <utility>
#include <vector>

#include "core/util/JsonSource.h"

namespace loom::test {

struct ComputeNodeSpec {
    std::string name;
    std::vector<std::string> inputs;      // rgba32f texture inputs
    std::vector<std::string> prevInputs;  // rgba32f inputs with "previousFrame": true
    std::vector<std::string> outputs;
    std::string outputFormat = "rgba32f";
    bool optionalOutputs = false;
};

inline std::string computeGraphText(const std::string& graphName,
                                    const std::vector<ComputeNodeSpec>& nodes,
                                    const std::vector<std::pair<std::string, std::string>>& edges,
                                    const std::vector<std::string>& outputs) {
    json g;
    g["name"] = graphName;
    for (const auto& n : nodes) {
        json in = json::object(), out = json::object();
        for (auto& i : n.inputs) in[i] = {{"format", "rgba32f"}};
        for (auto& i : n.prevInputs) in[i] = {{"format", "rgba32f"}, {"previousFrame", true}};
        for (auto& o : n.outputs)
            out[o] = {{"format", n.outputFormat}, {"optional", n.optionalOutputs}};
        g["passes"].push_back(
            {{"name", n.name},
             {"type", "ComputePass"},
             {"params", {{"shader", n.name + ".comp"}, {"inputs", in}, {"outputs", out}}}});
    }
    g["edges"] = json::array();
    for (auto& [a, b] : edges) g["edges"].push_back({a, b});
    g["outputs"] = outputs;
    return g.dump(2);
}

}  // namespace loom::test
