// Reservoir splatting (Liu et al. 2025): unbiasedness against the reference path tracer under
// camera motion (tests/support/ReuseComparison.h: sequences as the independent unit, 2x2 and
// 8x8 regions), the ablations that must be detected, splat conservation, and the shift's
// invertibility, Jacobian and MIS partition of unity in a probe kernel.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "core/graph/Renderer.h"
#include "core/scene/SceneLoader.h"
#include "tests/support/GpuSupport.h"
#include "tests/support/ReuseComparison.h"
#include "tests/support/TestSupport.h"

using namespace loom;
using namespace loom::test;

namespace {

std::map<std::string, double> passStats(Renderer& r, const std::string& pass) {
    for (auto& p : r.graph().passes())
        if (p->name() == pass) return p->stats();
    return {};
}

}  // namespace

// Camera motion: the Cornell box's and the glossy scene's camera paths (translation and
// rotation), and scenes/fine_geometry.json's, which also zooms and moves forward (holes).
TEST(ReservoirSplat, UnbiasedUnderCameraMotion) {
    struct Case {
        const char* scene;
        float dt;
    };
    for (Case c : {Case{"scenes/cornell_box.json", 3.0f}, Case{"scenes/glossy_spheres.json", 2.0f},
                   Case{"scenes/fine_geometry.json", 8.0f}}) {
        auto cmp = compareWithReference(sourcePath(c.scene), "splat.json", {}, c.dt);
        EXPECT_TRUE(cmp.unbiased()) << c.scene << ": " << cmp.restir << " vs " << cmp.reference;
    }
}

// Thin-lens depth of field: the lens sample is copied and x1 kept, so the splat needs no second
// shift and no heuristic MIS. Moving shapes: x1 keeps its barycentrics on the moving box, the
// forward projection and the reverse splat see each frame's geometry.
TEST(ReservoirSplat, UnbiasedWithDepthOfFieldAndMovingShapes) {
    scene::Scene lens = scene::loadScene(sourcePath("scenes/cornell_box.json"));
    lens.camera.type = scene::CameraType::ThinLens;
    lens.camera.apertureRadius = 0.4f;
    lens.camera.focusDistance = 5.5f;
    auto dof = compareWithReference(lens, "splat.json", {}, 3.0f);
    EXPECT_TRUE(dof.unbiased()) << "thin lens: " << dof.restir << " vs " << dof.reference;

    json scene = json::parse(readFile(sourcePath("scenes/cornell_box.json")));
    for (auto& shape : scene["shapes"])
        if (shape["name"] == "tall_box")
            shape["path"] = json::parse(R"([{"time": 0, "translate": [0, 0, 0]},
                {"time": 21, "translate": [0.35, 0, 0.05], "rotate": {"axis": [0, 1, 0], "angle": 50}}])");
    TempDir tmp("loom-splat-moving");
    std::string path = tmp / "cornell_moving.json";
    writeFile(path, scene.dump());
    auto moving = compareWithReference(scene::loadScene(path), "splat.json", {}, 3.0f);
    EXPECT_TRUE(moving.unbiased()) << "moving box: " << moving.restir << " vs " << moving.reference;
}

// The ablations of the paper's choices are biased and must be detected by the same test:
// without the canonical sample's reverse-splat term the weights of a path sum to more than 1;
// summing the landed splats' confidences makes the MIS weights depend on where the previous
// samples landed.
TEST(ReservoirSplat, AblationsAreDetected) {
    std::string scene = sourcePath("scenes/cornell_box.json");
    for (const char* ablation : {"noReverseSplat", "sumSplatConfidences"}) {
        auto c = compareWithReference(scene, "splat.json", {{"temporal.ablation", ablation}}, 3.0f);
        EXPECT_FALSE(c.unbiased()) << ablation << " was not detected";
    }
}
