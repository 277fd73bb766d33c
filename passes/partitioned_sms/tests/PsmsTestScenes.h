#pragma once
// Scenes of the partitioned-SMS tests by name: a path under the source tree, or the path with
// "#rough" appended for the same scene with its smooth conductors and dielectrics made rough
// (GGX, alpha 0.1): glossy casters, whose chains scatter about offset normals.
#include <string>

#include "core/scene/SceneLoader.h"
#include "tests/support/RoughCasters.h"

namespace loom::test {

inline scene::Scene loadPsmsScene(const std::string& spec) {
    const std::string kRough = "#rough";
    bool rough = spec.size() > kRough.size() &&
                 spec.compare(spec.size() - kRough.size(), kRough.size(), kRough) == 0;
    std::string path = rough ? spec.substr(0, spec.size() - kRough.size()) : spec;
    auto scene = scene::loadScene(std::string(LOOM_SOURCE_DIR) + "/" + path);
    if (rough) makeCastersRough(scene, 0.1f, scene::Microfacet::GGX);
    return scene;
}

}  // namespace loom::test
