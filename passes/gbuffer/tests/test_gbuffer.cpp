// GBuffer motion vectors against a CPU reprojection (core/scene/Camera.h), and rigid shape
// motion along keyframe paths (Shape::path): moving shapes render where their keyframes put
// them and their motion vectors include the shape's own motion.
#include <gtest/gtest.h>

#include <cmath>

#include "core/graph/Renderer.h"
#include "core/scene/Camera.h"
#include "core/scene/SceneGpu.h"
#include "core/scene/SceneLoader.h"
#include "tests/support/GpuSupport.h"

using namespace loom;

namespace {

constexpr uint32_t kW = 64, kH = 48;

// A wall (shape 0) behind a small cube (shape 1); `cameraPath` and `cubePath` are JSON arrays
// of keyframes ("" = none).
std::string sceneJson(const std::string& cameraPath, const std::string& cubePath) {
    std::string camera = R"("camera": {"origin": [0, 0, 5], "target": [0, 0, 0], "fov": 40)";
    if (!cameraPath.empty()) camera += R"(, "path": )" + cameraPath;
    camera += "}";
    std::string cube = R"({"name": "cube", "type": "cube", "transform": {"scale": 0.3})";
    if (!cubePath.empty()) cube += R"(, "path": )" + cubePath;
    cube += "}";
    return R"({"loom_scene": 1, )" + camera + R"(, "shapes": [
        {"name": "wall", "type": "rectangle",
         "transform": [{"scale": 4}, {"translate": [0, 0, -1]}]}, )" +
           cube + R"(], "lights": [{"type": "constant", "radiance": 1}]})";
}

struct Frame {
    ImageData vbuffer, motion, position, sample;
};

class GBufferMotion : public ::testing::Test {
protected:
    void load(const std::string& json) {
        std::string path = mTmp / "scene.json";
        test::writeFile(path, json);
        auto graph = RenderGraph::parse(R"({"name": "g", "passes": [
            {"name": "gbuf", "type": "GBuffer"}],
            "outputs": ["gbuf.vbuffer", "gbuf.motion", "gbuf.position", "gbuf.sample"]})",
                                        "<test>");
        mRenderer = std::make_unique<Renderer>(test::gpuContext(), std::move(graph), kW, kH, 3);
        mRenderer->loadScene(path);
    }
    Frame render(float time) {
        mRenderer->setTime(time);
        mRenderer->frame();
        return {mRenderer->readOutput("gbuf.vbuffer"), mRenderer->readOutput("gbuf.motion"),
                mRenderer->readOutput("gbuf.position"), mRenderer->readOutput("gbuf.sample")};
    }
    const scene::Scene& scene() { return mRenderer->scene()->cpu(); }

    // Film position in pixels of world point p seen by the scene camera at `time`, derived
    // from the camera-to-world matrix (Mitsuba frame: +x left, +y up, +z forward) and the
    // vertical fov, independently of the shader's camera_project.
    glm::dvec2 project(float time, const glm::vec3& p) {
        scene::Camera c = scene::cameraAt(scene().camera, time);
        glm::dvec3 o(c.toWorld[3]), left(c.toWorld[0]), up(c.toWorld[1]), fwd(c.toWorld[2]);
        left = glm::normalize(left), up = glm::normalize(up), fwd = glm::normalize(fwd);
        glm::dvec3 v = glm::dvec3(p) - o;
        double z = glm::dot(v, fwd);
        double ty = std::tan(glm::radians(double(c.fov)) * 0.5), tx = ty * kW / kH;
        return {0.5 * (1.0 - glm::dot(v, left) / z / tx) * kW,
                0.5 * (1.0 - glm::dot(v, up) / z / ty) * kH};
    }
    // The expected motion vector of pixel (x, y) of frame `f` rendered at time `now` after
    // time `prev`: its hit point moved with its shape, reprojected into the previous camera.
    glm::dvec2 expectedMotion(const Frame& f, uint32_t x, uint32_t y, float now, float prev) {
        glm::vec3 p(f.position.at(x, y, 0), f.position.at(x, y, 1), f.position.at(x, y, 2));
        const scene::Shape& shape = scene().shapes[size_t(f.vbuffer.at(x, y, 3))];
        glm::dmat4 m = glm::dmat4(scene::shapeToWorldAt(shape, prev)) *
                       glm::inverse(glm::dmat4(scene::shapeToWorldAt(shape, now)));
        glm::vec3 pPrev = glm::vec3(m * glm::dvec4(p, 1.0));
        glm::dvec2 film(x + f.sample.at(x, y, 0), y + f.sample.at(x, y, 1));
        return project(prev, pPrev) - film;
    }
    static bool hit(const Frame& f, uint32_t x, uint32_t y) { return f.position.at(x, y, 3) > 0; }
    static glm::dvec2 motion(const Frame& f, uint32_t x, uint32_t y) {
        return {f.motion.at(x, y, 0), f.motion.at(x, y, 1)};
    }

    test::TempDir mTmp{"loom-gbuffer"};
    std::unique_ptr<Renderer> mRenderer;
};

}  // namespace

TEST_F(GBufferMotion, StaticCameraGivesZero) {
    load(sceneJson("", ""));
    render(0.0f);
    Frame f = render(1.0f);  // a new frame time, nothing moves
    uint32_t hits = 0;
    for (uint32_t y = 0; y < kH; ++y)
        for (uint32_t x = 0; x < kW; ++x) {
            if (!hit(f, x, y)) continue;
            ++hits;
            ASSERT_LT(glm::length(motion(f, x, y)), 1e-3) << x << "," << y;
        }
    EXPECT_EQ(hits, kW * kH);  // the wall fills the view
}

TEST_F(GBufferMotion, CameraPathMatchesCpuReprojection) {
    load(sceneJson(R"([{"time": 0}, {"time": 1, "origin": [0.6, 0.4, 4.5], "target": [0.2, 0, 0],
                       "fov": 44}])",
                   ""));
    render(0.0f);
    // The previous frame is the last one rendered: a second frame at time 1 (new film jitter)
    // has no motion, as the history it reuses was made at time 1.
    for (int repeat = 0; repeat < 2; ++repeat) {
        Frame f = render(1.0f);
        float prev = repeat == 0 ? 0.0f : 1.0f;
        double maxErr = 0.0, maxMotion = 0.0;
        for (uint32_t y = 0; y < kH; ++y)
            for (uint32_t x = 0; x < kW; ++x) {
                if (!hit(f, x, y)) continue;
                glm::dvec2 e = expectedMotion(f, x, y, 1.0f, prev);
                maxErr = std::max(maxErr, glm::length(motion(f, x, y) - e));
                maxMotion = std::max(maxMotion, glm::length(e));
            }
        if (repeat == 0) {
            EXPECT_GT(maxMotion, 3.0);  // the camera really moved (pixels)
        } else {
            EXPECT_LT(maxMotion, 1e-3);  // pixels
        }
        EXPECT_LT(maxErr, 2e-3) << "pixels, repeat " << repeat;
    }
}

TEST_F(GBufferMotion, MovingShapeRendersAtKeyframedPlace) {
    load(sceneJson("", R"([{"time": 0, "translate": [-1, 0, 0]},
                         {"time": 2, "translate": [1, 0.3, 0.5],
                          "rotate": {"axis": [0, 0, 1], "angle": 60}}])"));
    const scene::Shape& cube = scene().shapes[1];
    for (float t : {0.0f, 1.0f, 2.0f, 0.5f}) {
        SCOPED_TRACE(t);
        Frame f = render(t);
        glm::mat4 toWorld = scene::shapeToWorldAt(cube, t);
        // The pixel on the cube's centre shows the cube; where it is at the other end of its
        // path shows the wall.
        glm::vec3 centre = glm::vec3(toWorld[3]);
        glm::dvec2 c = project(t, centre);
        EXPECT_EQ(f.vbuffer.at(uint32_t(c.x), uint32_t(c.y), 3), 1.0f);
        glm::dvec2 other = project(t, glm::vec3(scene::shapeToWorldAt(cube, 2.0f - t)[3]));
        if (t != 1.0f) {
            EXPECT_EQ(f.vbuffer.at(uint32_t(other.x), uint32_t(other.y), 3), 0.0f);
        }
        // Every cube hit lies on the cube as the keyframes place it at time t.
        glm::mat4 toObject = glm::inverse(toWorld);
        uint32_t cubePixels = 0;
        for (uint32_t y = 0; y < kH; ++y)
            for (uint32_t x = 0; x < kW; ++x) {
                if (f.vbuffer.at(x, y, 3) != 1.0f) continue;
                ++cubePixels;
                glm::vec3 p(f.position.at(x, y, 0), f.position.at(x, y, 1), f.position.at(x, y, 2));
                glm::vec3 q = glm::vec3(toObject * glm::vec4(p, 1.0f));
                ASSERT_LT(std::max({std::abs(q.x), std::abs(q.y), std::abs(q.z)}), 1.0f + 1e-4f)
                    << x << "," << y;
            }
        EXPECT_GT(cubePixels, 20u);
    }
}

TEST_F(GBufferMotion, MovingShapeMotionMatchesCpuReprojection) {
    // Camera and cube both move; the cube also turns, so its motion is not a translation.
    load(sceneJson(R"([{"time": 0}, {"time": 1, "origin": [0.3, 0.2, 4.8]}])",
                   R"([{"time": 0, "translate": [-0.5, 0, 0]},
                       {"time": 1, "translate": [0.3, -0.2, 0.4],
                        "rotate": {"axis": [1, 1, 0], "angle": 35}}])"));
    render(0.0f);
    Frame f = render(1.0f);
    double maxErr = 0.0, maxShapeMotion = 0.0;
    uint32_t cubePixels = 0;
    const scene::Shape& wall = scene().shapes[0];
    for (uint32_t y = 0; y < kH; ++y)
        for (uint32_t x = 0; x < kW; ++x) {
            if (!hit(f, x, y)) continue;
            glm::dvec2 e = expectedMotion(f, x, y, 1.0f, 0.0f);
            maxErr = std::max(maxErr, glm::length(motion(f, x, y) - e));
            if (f.vbuffer.at(x, y, 3) != 1.0f) continue;
            ++cubePixels;
            // How far the cube's own motion moves the pixel beyond the camera's.
            glm::vec3 p(f.position.at(x, y, 0), f.position.at(x, y, 1), f.position.at(x, y, 2));
            glm::dvec2 film(x + f.sample.at(x, y, 0), y + f.sample.at(x, y, 1));
            glm::dvec2 cameraOnly = project(0.0f, p) - film;
            maxShapeMotion = std::max(maxShapeMotion, glm::length(e - cameraOnly));
        }
    EXPECT_TRUE(wall.path.empty());
    EXPECT_GT(cubePixels, 20u);
    EXPECT_GT(maxShapeMotion, 3.0);  // pixels: the shape's motion is in the vectors
    EXPECT_LT(maxErr, 2e-3) << "pixels";
    // The same time again: the previous frame is the last one, nothing moved since.
    Frame again = render(1.0f);
    double maxAgain = 0.0;
    for (uint32_t y = 0; y < kH; ++y)
        for (uint32_t x = 0; x < kW; ++x)
            if (hit(again, x, y)) maxAgain = std::max(maxAgain, glm::length(motion(again, x, y)));
    EXPECT_LT(maxAgain, 1e-3) << "pixels";
}

namespace {

// PathTracer alone, or fed the first sample's primary hits by a GBuffer (graphs/pt.json).
ImageData pathTrace(bool withGBuffer, bool gbufferJitter) {
    std::string passes = R"({"name": "pt", "type": "PathTracer",
                             "params": {"maxBounces": 3, "motionBlur": false}})";
    std::string edges;
    if (withGBuffer) {
        passes += R"(, {"name": "gbuf", "type": "GBuffer",
                        "params": {"motionBlur": false, "jitter": )" +
                  std::string(gbufferJitter ? "true" : "false") + "}}";
        edges = R"(["gbuf.vbuffer", "pt.vbuffer"], ["gbuf.sample", "pt.sample"])";
    }
    auto graph = RenderGraph::parse(R"({"name": "pt", "passes": [)" + passes + R"(], "edges": [)" +
                                        edges + R"(], "outputs": ["pt.color"]})",
                                    "<test>");
    Renderer r(test::gpuContext(), std::move(graph), 32, 32, 5);
    r.loadScene(std::string(LOOM_SOURCE_DIR) + "/scenes/cornell_box.json");
    r.frames(2);
    return r.readOutput("pt.color");
}

}  // namespace

TEST(PathTracerGBuffer, PrimaryHitsFromTheGBufferGiveTheSameImage) {
    // The GBuffer draws the film and lens sample from the same stream positions as the path
    // tracer's first sample and its trace is the same, so the images are identical.
    ImageData alone = pathTrace(false, true);
    ImageData fed = pathTrace(true, true);
    ASSERT_EQ(alone.pixels.size(), fed.pixels.size());
    double sum = 0.0;
    for (size_t i = 0; i < alone.pixels.size(); ++i) {
        ASSERT_EQ(alone.pixels[i], fed.pixels[i]) << "pixel " << i / 4;
        sum += alone.pixels[i];
    }
    EXPECT_GT(sum, 0.0);
    // The inputs are really used: pixel-centre GBuffer samples change the image.
    ImageData centres = pathTrace(true, false);
    size_t differ = 0;
    for (size_t i = 0; i < alone.pixels.size(); ++i) differ += alone.pixels[i] != centres.pixels[i];
    EXPECT_GT(differ, alone.pixels.size() / 4);
}
