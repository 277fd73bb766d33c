#include "core/scene/Camera.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>

namespace loom::scene {

glm::mat4 lookAtMatrix(const glm::vec3& origin, const glm::vec3& target, const glm::vec3& up) {
    glm::vec3 dir = glm::normalize(target - origin);
    glm::vec3 left = glm::cross(up, dir);
    // An up vector parallel to the view direction has no frame; pick any perpendicular axis
    // rather than producing NaNs.
    if (glm::length(left) < 1e-8f)
        left = glm::cross(std::fabs(dir.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0), dir);
    left = glm::normalize(left);
    glm::vec3 newUp = glm::cross(dir, left);
    glm::mat4 m(1.0f);
    m[0] = glm::vec4(left, 0.0f);
    m[1] = glm::vec4(newUp, 0.0f);
    m[2] = glm::vec4(dir, 0.0f);
    m[3] = glm::vec4(origin, 1.0f);
    return m;
}

Camera cameraAt(const Camera& camera, float time) {
    if (camera.path.empty()) return camera;
    const std::vector<CameraKeyframe>& path = camera.path;
    CameraKeyframe k = path.front();
    if (time >= path.back().time) {
        k = path.back();
    } else if (time > path.front().time) {
        // First keyframe strictly after `time`; the segment is [it - 1, it].
        auto it = std::upper_bound(path.begin(), path.end(), time,
                                   [](float t, const CameraKeyframe& kf) { return t < kf.time; });
        const CameraKeyframe& a = *(it - 1);
        const CameraKeyframe& b = *it;
        float span = b.time - a.time;
        float t = span > 0.0f ? (time - a.time) / span : 0.0f;
        k.time = time;
        k.origin = glm::mix(a.origin, b.origin, t);
        k.target = glm::mix(a.target, b.target, t);
        k.up = glm::mix(a.up, b.up, t);
        k.fovY = a.fovY + (b.fovY - a.fovY) * t;
    }
    Camera result = camera;
    result.toWorld = lookAtMatrix(k.origin, k.target, k.up);
    result.fov = k.fovY;
    result.fovAxis = Camera::FovAxis::Y;
    return result;
}

glm::mat4 shapeToWorldAt(const Shape& shape, float time) {
    if (shape.path.empty()) return shape.toWorld;
    const std::vector<ShapeKeyframe>& path = shape.path;
    ShapeKeyframe k = path.front();
    if (time >= path.back().time) {
        k = path.back();
    } else if (time > path.front().time) {
        auto it = std::upper_bound(path.begin(), path.end(), time,
                                   [](float t, const ShapeKeyframe& kf) { return t < kf.time; });
        const ShapeKeyframe& a = *(it - 1);
        const ShapeKeyframe& b = *it;
        float span = b.time - a.time;
        float t = span > 0.0f ? (time - a.time) / span : 0.0f;
        k.translate = glm::mix(a.translate, b.translate, t);
        k.rotate = glm::slerp(a.rotate, b.rotate, t);  // shortest arc
        k.scale = glm::mix(a.scale, b.scale, t);
    }
    glm::mat4 m = glm::translate(glm::mat4(1.0f), k.translate) * glm::mat4_cast(k.rotate) *
                  glm::scale(glm::mat4(1.0f), k.scale);
    return m * shape.toWorld;
}

}  // namespace loom::scene
