// A MuJoCo model and its data from MJCF text, for the render tests and benchmarks that write their
// scene inline: the text is written to a file and loaded from there, its data forward-computed so
// that bodies and cameras stand where the model puts them.
#pragma once

#include <mujoco/mujoco.h>

#include <fstream>
#include <stdexcept>
#include <string>

namespace uavsim::testing {

class MjcfScene {
 public:
  // Writes xml to path and loads it; throws std::runtime_error "path: MuJoCo's message" when
  // MuJoCo refuses the model.
  MjcfScene(const std::string& xml, const std::string& path) {
    std::ofstream(path) << xml;
    char error[1000] = "";
    m = mj_loadXML(path.c_str(), nullptr, error, sizeof(error));
    if (m == nullptr) throw std::runtime_error(path + ": " + error);
    d = mj_makeData(m);
    mj_forward(m, d);
  }
  ~MjcfScene() {
    mj_deleteData(d);
    mj_deleteModel(m);
  }
  MjcfScene(const MjcfScene&) = delete;
  MjcfScene& operator=(const MjcfScene&) = delete;

  mjModel* m = nullptr;
  mjData* d = nullptr;
};

}  // namespace uavsim::testing
