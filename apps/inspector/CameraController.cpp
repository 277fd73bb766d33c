#include "apps/inspector/CameraController.h"

#include <algorithm>
#include <cmath>

#include "core/scene/Camera.h"

namespace loom::inspector {

namespace {
constexpr float kMaxPitch = 1.55f;  // just short of +-90 degrees: the frame stays defined
}

void CameraController::reset(const scene::Camera& camera, const glm::vec4& sphere) {
    mBase = camera;
    mBase.path.clear();
    glm::vec3 origin(camera.toWorld[3]);
    glm::vec3 dir = glm::normalize(glm::vec3(camera.toWorld[2]));
    glm::vec3 up = glm::vec3(camera.toWorld[1]);
    mUp = glm::length(up) > 1e-6f ? glm::normalize(up) : glm::vec3(0, 1, 0);
    // Orbit frame: mAxisA is the initial heading projected onto the horizontal plane.
    glm::vec3 flat = dir - glm::dot(dir, mUp) * mUp;
    if (glm::length(flat) < 1e-4f)
        flat = glm::cross(mUp, std::fabs(mUp.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0));
    mAxisA = glm::normalize(flat);
    mAxisB = glm::cross(mUp, mAxisA);
    mYaw = 0.0f;
    mPitch = std::asin(std::clamp(glm::dot(dir, mUp), -1.0f, 1.0f));
    mRadius = sphere.w > 0.0f ? sphere.w : 1.0f;
    float along = glm::dot(glm::vec3(sphere) - origin, dir);
    mDistance = along > 1e-3f * mRadius ? along : mRadius;
    mPivot = origin + dir * mDistance;
}

glm::vec3 CameraController::direction() const {
    return std::cos(mPitch) * (std::cos(mYaw) * mAxisA + std::sin(mYaw) * mAxisB) +
           std::sin(mPitch) * mUp;
}

void CameraController::orbit(float dYaw, float dPitch) {
    mYaw += dYaw;
    mPitch = std::clamp(mPitch + dPitch, -kMaxPitch, kMaxPitch);
}

void CameraController::pan(float dx, float dy) {
    glm::vec3 dir = direction();
    glm::vec3 left = glm::normalize(glm::cross(mUp, dir));  // Mitsuba: local +x is left
    glm::vec3 up = glm::cross(dir, left);
    mPivot += (left * dx + up * dy) * mDistance;
}

void CameraController::dolly(float steps) {
    mDistance = std::max(mDistance * std::pow(0.9f, steps), 1e-4f * mRadius);
}

void CameraController::fly(const glm::vec3& move) {
    glm::vec3 dir = direction();
    glm::vec3 left = glm::normalize(glm::cross(mUp, dir));
    glm::vec3 up = glm::cross(dir, left);
    mPivot += (-left * move.x + up * move.y + dir * move.z) * mRadius;
}

void CameraController::look(float dYaw, float dPitch) {
    glm::vec3 eye = origin();
    orbit(dYaw, dPitch);
    mPivot = eye + direction() * mDistance;  // turn about the eye, not the pivot
}

scene::Camera CameraController::camera() const {
    scene::Camera c = mBase;
    c.toWorld = scene::lookAtMatrix(origin(), mPivot, mUp);
    return c;
}

}  // namespace loom::inspector
