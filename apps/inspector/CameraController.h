#pragma once
// Orbit and fly camera controls for the inspector, on top of the scene's camera. Window-free:
// the app turns mouse and keys into these calls.
#include "core/scene/Scene.h"

namespace loom::inspector {

class CameraController {
public:
    // Starts from a scene camera (its pose at the current time when it has a path); the orbit
    // pivot is the point along the view direction nearest the scene's bounding-sphere centre.
    void reset(const scene::Camera& camera, const glm::vec4& boundingSphere);
    // Orbit around the pivot (radians; pitch is clamped short of the poles).
    void orbit(float dYaw, float dPitch);
    // Move the pivot in the view plane, in units of the pivot distance.
    void pan(float dx, float dy);
    // Move towards (steps > 0) or away from the pivot; each step is 10 % of the distance.
    void dolly(float steps);
    // Fly: move the eye by (right, up, forward) in units of the scene radius.
    void fly(const glm::vec3& move);
    // Fly: turn the view direction in place.
    void look(float dYaw, float dPitch);

    // The scene camera with this pose (path removed, so the pose sticks).
    scene::Camera camera() const;
    glm::vec3 origin() const { return mPivot - direction() * mDistance; }
    glm::vec3 target() const { return mPivot; }
    glm::vec3 direction() const;
    float distance() const { return mDistance; }

private:
    scene::Camera mBase;
    glm::vec3 mUp{0, 1, 0}, mAxisA{0, 0, 1}, mAxisB{1, 0, 0};  // world frame around mUp
    glm::vec3 mPivot{0.0f};
    float mYaw = 0.0f, mPitch = 0.0f, mDistance = 1.0f, mRadius = 1.0f;
};

}  // namespace loom::inspector
