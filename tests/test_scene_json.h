// A tiny scene file (JSON) for the command-line and quality-suite tests.
#pragma once

#include <array>

#include <nlohmann/json.hpp>

namespace deltagi::test {

// A floor quad (explicit triangles), a 0.3 box on it as the virtual object (of `boxAlbedo`) and one point
// light, width x height pixels, 16^3 volumes: small enough to render in well under a second.
inline nlohmann::json tinySceneJson(int width, int height, std::array<double, 3> boxAlbedo) {
    const nlohmann::json floorShape = {{"type", "triangles"},
                                       {"positions", {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}}},
                                       {"indices", {{0, 2, 1}, {0, 3, 2}}}};
    return {
        {"camera",
         {{"width", width},
          {"height", height},
          {"fov_y_deg", 45},
          {"position", {0, 0.8, 2}},
          {"look_at", {0, 0.1, 0}},
          {"up", {0, 1, 0}}}},
        {"scene", {{{"name", "floor"}, {"shape", floorShape}, {"material", {{"albedo", {0.7, 0.7, 0.7}}}}}}},
        {"virtual",
         {{{"name", "box"},
           {"shape", {{"type", "box"}, {"size", {0.3, 0.3, 0.3}}}},
           {"transform", {{"translate", {0, 0.15, 0}}}},
           {"material", {{"albedo", boxAlbedo}}}}}},
        {"lights", {{{"type", "point"}, {"position", {0.5, 1.5, 0.5}}, {"intensity", 3}}}},
        {"options", {{"volume", {{"resolution", 16}}}, {"rsm", {{"resolution", 64}}}}},
    };
}

}  // namespace deltagi::test
