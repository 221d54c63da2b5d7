// A scene built in code, rendered in a few frames while its virtual ball moves; the last frame is written.
//   embed OUT.png
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "deltagi/error.h"
#include "deltagi/renderer.h"
#include "deltagi/shapes.h"
#include "deltagi/transforms.h"

int main(int argc, char** argv) {
    if (argc != 2) return std::fprintf(stderr, "usage: embed OUT.png\n"), 2;
    try {
        deltagi::Scene scene;
        scene.camera.width = 160;
        scene.camera.height = 120;
        scene.camera.setFieldOfView(50.0);
        scene.camera.worldFromCamera = deltagi::lookAtPose({0.0f, 1.2f, 2.0f}, {0.0f, 0.2f, 0.0f});

        deltagi::TriangleMesh floor = deltagi::makeQuad({3.0f, 3.0f});  // the real scene: y = 0, normal +y
        floor.name = "floor";
        floor.material.albedo = glm::vec3(0.6f);
        deltagi::setTransform(floor, glm::mat4(1.0f));  // checked as the scene reader checks a mesh
        scene.real = {floor};

        deltagi::TriangleMesh ball = deltagi::makeSphere(0.25f, 32);  // the virtual object
        ball.name = "ball";
        ball.material.albedo = {0.1f, 0.25f, 0.8f};
        scene.virtuals = {ball};

        deltagi::Light light;  // a point light, 4 W/sr
        light.position = {0.5f, 2.0f, 1.0f};
        light.intensity = 4.0f;
        scene.lights = {light};
        scene.options.volume.resolution = 32;

        deltagi::FrameRenderer frames;  // keeps the real scene's work while only the ball moves
        deltagi::RenderOutput out;
        for (int frame = 0; frame < 3; ++frame) {
            glm::vec3 position(0.15f * static_cast<float>(frame), 0.25f, 0.1f);
            deltagi::setTransform(scene.virtuals[0], glm::translate(glm::mat4(1.0f), position));
            out = frames.render(scene);  // composite, background, objectMask, delta, timings
            std::printf("frame %d: %.1f ms\n", frame, out.totalMs);
        }
        deltagi::writeImage(out.composite, argv[1]);
    } catch (const deltagi::InputError& e) {
        std::fprintf(stderr, "embed: error: %s\n", e.what());
        return 1;
    }
}
