// Inspector parameter widgets generated from pass declarations, edits through the graph's
// validation, and saving edited graphs back to JSON. No window, no GPU.
#include <gtest/gtest.h>

#include "apps/inspector/GraphFile.h"
#include "apps/inspector/ParamWidgets.h"
#include "core/graph/RenderGraph.h"
#include "tests/support/TestSupport.h"

namespace {

using loom::json;
using loom::ParamDesc;
using loom::ParamType;
using loom::RenderGraph;
using loom::inspector::applyParam;
using loom::inspector::paramWidget;
using loom::inspector::paramWidgets;
using loom::inspector::WidgetKind;

const loom::inspector::ParamWidget* find(const std::vector<loom::inspector::ParamWidget>& ws,
                                         const std::string& name) {
    for (const auto& w : ws)
        if (w.name == name) return &w;
    return nullptr;
}

TEST(InspectorWidgets, FromToneMapDeclaration) {
    auto g = RenderGraph::parse(
        R"({"passes": [{"name": "tm", "type": "ToneMap"}], "outputs": ["tm.output"]})", "w.json");
    auto ws = paramWidgets(g->findPass("tm")->reflection());
    const auto* exposure = find(ws, "exposure");
    ASSERT_NE(exposure, nullptr);
    EXPECT_EQ(exposure->kind, WidgetKind::SliderFloat);  // declared range(-20, 20)
    EXPECT_EQ(*exposure->min, -20.0);
    EXPECT_EQ(*exposure->max, 20.0);
    EXPECT_NE(exposure->tooltip.find("EV"), std::string::npos);  // the declaration's doc
    const auto* op = find(ws, "operator");
    ASSERT_NE(op, nullptr);
    EXPECT_EQ(op->kind, WidgetKind::Combo);
    EXPECT_EQ(op->choices, (std::vector<std::string>{"clamp", "reinhard", "aces"}));
    const auto* srgb = find(ws, "srgb");
    ASSERT_NE(srgb, nullptr);
    EXPECT_EQ(srgb->kind, WidgetKind::Checkbox);
}

TEST(InspectorWidgets, KindsFromTypesAndRanges) {
    auto make = [](ParamType t, json def, std::optional<double> lo = {},
                   std::optional<double> hi = {}) {
        ParamDesc d;
        d.name = "p";
        d.type = t;
        d.defaultValue = def;
        d.min = lo;
        d.max = hi;
        return paramWidget(d);
    };
    EXPECT_EQ(make(ParamType::Int, 4, 0, 16).kind, WidgetKind::SliderInt);
    EXPECT_EQ(make(ParamType::Int, 0, 0).kind, WidgetKind::DragInt);  // open range: drag
    EXPECT_EQ(make(ParamType::Int, 0, 0, 1e9).kind, WidgetKind::DragInt);
    EXPECT_EQ(make(ParamType::Float, 1.0).kind, WidgetKind::DragFloat);
    auto lg = make(ParamType::Float, 0.01, 1e-4, 10.0);
    EXPECT_EQ(lg.kind, WidgetKind::SliderFloat);
    EXPECT_TRUE(lg.logarithmic);
    EXPECT_FALSE(make(ParamType::Float, 0.5, 0.0, 1.0).logarithmic);
    auto v3 = make(ParamType::Vec3, json::array({1, 20, 3}));
    EXPECT_EQ(v3.kind, WidgetKind::Vector);
    EXPECT_EQ(v3.components, 3);
    EXPECT_FLOAT_EQ(v3.dragSpeed, 0.2f);  // 1 % of the largest default component
    EXPECT_EQ(make(ParamType::Vec4, json::array({0, 0, 0, 0})).components, 4);
    EXPECT_EQ(make(ParamType::String, "x").kind, WidgetKind::Text);
    EXPECT_EQ(make(ParamType::Json, json::object()).kind, WidgetKind::JsonText);
    EXPECT_NE(make(ParamType::Int, 4, 0, 16).tooltip.find("range [0"), std::string::npos);
}

TEST(InspectorWidgets, ComputePassConstantsBecomeWidgets) {
    auto g = RenderGraph::load(std::string(LOOM_SOURCE_DIR) + "/graphs/hello_compute.json");
    auto ws = paramWidgets(g->findPass("scene")->reflection());
    const auto* sun = find(ws, "sunIntensity");
    ASSERT_NE(sun, nullptr);
    EXPECT_EQ(sun->kind, WidgetKind::DragFloat);  // min 0, no max
    EXPECT_EQ(*sun->min, 0.0);
    const auto* shader = find(ws, "shader");
    ASSERT_NE(shader, nullptr);
    EXPECT_EQ(shader->kind, WidgetKind::Text);
}

TEST(InspectorWidgets, EditsAreValidatedNeverThrow) {
    auto g = RenderGraph::parse(
        R"({"passes": [{"name": "tm", "type": "ToneMap"}], "outputs": ["tm.output"]})", "w.json");
    EXPECT_EQ(applyParam(*g, "tm", "exposure", 2.5), "");
    EXPECT_EQ(g->getParam("tm.exposure"), json(2.5));
    std::string err = applyParam(*g, "tm", "exposure", 99.0);  // out of range
    EXPECT_NE(err, "");
    EXPECT_NE(err.find("exposure"), std::string::npos) << err;
    EXPECT_EQ(g->getParam("tm.exposure"), json(2.5));  // unchanged
    EXPECT_NE(applyParam(*g, "tm", "operator", "filmic"), "");
    EXPECT_NE(applyParam(*g, "nope", "exposure", 1.0), "");
    json v;
    EXPECT_EQ(loom::inspector::parseJsonText("[1, 2]", v), "");
    EXPECT_EQ(v, json::array({1, 2}));
    EXPECT_NE(loom::inspector::parseJsonText("[1, ", v), "");
}

TEST(InspectorWidgets, SaveEditedGraphRoundTrips) {
    loom::test::TempDir dir("loom-inspector");
    auto g = RenderGraph::load(std::string(LOOM_SOURCE_DIR) + "/graphs/pt.json");
    ASSERT_EQ(applyParam(*g, "tm", "exposure", -1.25), "");
    ASSERT_EQ(applyParam(*g, "tm", "operator", "reinhard"), "");
    ASSERT_EQ(applyParam(*g, "pt", "maxBounces", 3), "");
    std::string path = dir / "edited.json";
    EXPECT_EQ(loom::inspector::saveGraphChecked(*g, path), "");
    auto back = RenderGraph::load(path);
    EXPECT_TRUE(back->equals(*g));
    EXPECT_EQ(back->getParam("tm.exposure"), json(-1.25));
    EXPECT_EQ(back->getParam("tm.operator"), json("reinhard"));
    EXPECT_EQ(back->getParam("pt.maxBounces"), json(3));
    // An unwritable path (under a regular file) is an error message, not an exception, and a
    // missing directory is created, as for every file Loom writes.
    EXPECT_NE(loom::inspector::saveGraphChecked(*g, dir / "edited.json/x.json"), "");
    EXPECT_EQ(loom::inspector::saveGraphChecked(*g, dir / "missing/dir/x.json"), "");
}

TEST(InspectorWidgets, FileWatcherSeesChanges) {
    loom::test::TempDir dir("loom-inspector");
    std::string path = dir / "g.json";
    loom::test::writeFile(path, "{}");
    loom::inspector::FileWatcher w(path);
    EXPECT_FALSE(w.changed());
    loom::test::writeFile(path, "{\"name\": \"x\"}");  // a different size is enough
    EXPECT_TRUE(w.changed());
    EXPECT_FALSE(w.changed());
}

}  // namespace
