#include "uavsim/common/install_paths.hpp"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace uavsim::common {

namespace fs = std::filesystem;

namespace {

// a models directory is one that holds worlds/ (the server's shipped worlds by name)
bool holds_worlds(const fs::path& dir) {
  std::error_code ec;
  return !dir.empty() && fs::is_directory(dir / "worlds", ec);
}

}  // namespace

ModelsDir find_models_dir(const ModelsDirSearch& search) {
  // what the user named wins, even when it is wrong: the error then names it
  if (!search.option.empty()) return {search.option, ModelsDirSource::kOption};
  if (!search.environment.empty()) return {search.environment, ModelsDirSource::kEnvironment};
  // an install: PREFIX/bin/program and PREFIX/share/uavsim/models
  fs::path installed;
  if (!search.executable_dir.empty()) {
    installed =
        (fs::path(search.executable_dir) / ".." / kInstalledModelsSubdir).lexically_normal();
    if (holds_worlds(installed)) return {installed.string(), ModelsDirSource::kInstall};
  }
  // the build tree: the source tree it was configured from
  if (holds_worlds(search.source_tree)) return {search.source_tree, ModelsDirSource::kSourceTree};
  return {installed.empty() ? search.source_tree : installed.string(), ModelsDirSource::kNone};
}

ModelsDir find_models_dir(const std::string& option, const std::string& source_tree) {
  ModelsDirSearch s;
  s.option = option;
  if (const char* env = std::getenv("UAVSIM_MODELS_DIR")) s.environment = env;
  s.executable_dir = executable_dir();
  s.source_tree = source_tree;
  return find_models_dir(s);
}

std::string executable_dir() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : self.parent_path().string();
}

std::string installed_or_built_program(const std::string& name, const std::string& built_path) {
  const std::string dir = executable_dir();
  if (!dir.empty()) {
    const fs::path beside = fs::path(dir) / name;
    std::error_code ec;
    if (fs::is_regular_file(beside, ec) && access(beside.c_str(), X_OK) == 0)
      return beside.string();
  }
  return built_path;
}

const char* to_string(ModelsDirSource from) {
  switch (from) {
    case ModelsDirSource::kOption:
      return "--models-dir";
    case ModelsDirSource::kEnvironment:
      return "UAVSIM_MODELS_DIR";
    case ModelsDirSource::kInstall:
      return "install";
    case ModelsDirSource::kSourceTree:
      return "source tree";
    case ModelsDirSource::kNone:
      break;
  }
  return "none";
}

}  // namespace uavsim::common
