#pragma once
// Animation helpers shared by the loaders and the renderer: Mitsuba's look-at frame, keyframed
// camera paths and keyframed rigid shape motion.
#include "core/scene/Scene.h"

namespace loom::scene {

// Camera-to-world matrix in Mitsuba's look-at convention: local +z looks from origin to target,
// local +x = normalize(cross(up, dir)) (left in the image), local +y = cross(dir, x) (up).
glm::mat4 lookAtMatrix(const glm::vec3& origin, const glm::vec3& target, const glm::vec3& up);

// The camera at animation time `time` (frames). Without a path the camera is returned as is.
// With a path, origin, target, up and vertical fov are interpolated linearly between the two
// keyframes around `time` (clamped to the first/last keyframe), toWorld is rebuilt with
// lookAtMatrix() and fov/fovAxis become the keyframe's vertical fov. Keyframes must be sorted
// by time (the loaders sort them).
Camera cameraAt(const Camera& camera, float time);

// Object to world of `shape` at animation time `time` (frames): shape.toWorld without a path;
// with one, M(time) * toWorld where M = translate * rotate * scale of the keyframes around
// `time`, translation and scale interpolated linearly, rotation by slerp, clamped to the first
// and last keyframe.
glm::mat4 shapeToWorldAt(const Shape& shape, float time);

}  // namespace loom::scene
