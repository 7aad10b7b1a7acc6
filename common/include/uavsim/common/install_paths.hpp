// Where an installed or a built uavsim finds its shipped models and its sibling programs, so that
// the same binary works from the build tree (models from the source tree, programs in their build
// folders) and from an install prefix (PREFIX/bin beside PREFIX/share/uavsim/models), with no
// source tree and no option. Filesystem look-ups only: no sockets, no threads.
#pragma once

#include <string>

namespace uavsim::common {

// Where the models directory came from (ModelsDir::from).
enum class ModelsDirSource {
  kOption,       // an explicit --models-dir
  kEnvironment,  // the environment variable UAVSIM_MODELS_DIR
  kInstall,      // PREFIX/share/uavsim/models beside this program's PREFIX/bin
  kSourceTree,   // the source tree's models/ the build was configured from
  kNone,         // none of them holds worlds/: path is the install location the program expected
};

// The inputs of the search, each empty when absent; find_models_dir() below fills them from the
// process.
struct ModelsDirSearch {
  std::string option;          // --models-dir as given
  std::string environment;     // the value of UAVSIM_MODELS_DIR
  std::string executable_dir;  // the folder of the running program
  std::string source_tree;     // the build's models/ (compiled in)
};

struct ModelsDir {
  std::string path;
  ModelsDirSource from = ModelsDirSource::kNone;
};

// The subpath of an install prefix that holds the models ("share/uavsim/models").
inline constexpr const char* kInstalledModelsSubdir = "share/uavsim/models";

// The models directory, first of: the option (taken as given: a wrong one must fail with its own
// name, not be skipped silently), the environment variable (likewise), the install
// (executable_dir/../share/uavsim/models) when it holds worlds/, the source tree when it holds
// worlds/. With none of them, kNone and the install location. Thread-safe.
ModelsDir find_models_dir(const ModelsDirSearch& search);

// The same search for this process: option as given, UAVSIM_MODELS_DIR from the environment, the
// folder of /proc/self/exe, and source_tree (the caller's compiled-in UAVSIM_MODELS_DIR, or "").
// Thread-safe (reads the environment).
ModelsDir find_models_dir(const std::string& option, const std::string& source_tree);

// The folder of the running program ("" when /proc/self/exe cannot be read). Thread-safe.
std::string executable_dir();

// A program that ships with uavsim: NAME beside the running program when it is there (the install:
// every program in PREFIX/bin), else built_path (where the build tree put it). Thread-safe.
std::string installed_or_built_program(const std::string& name, const std::string& built_path);

// "--models-dir", "UAVSIM_MODELS_DIR", "install", "source tree", "none": for messages.
const char* to_string(ModelsDirSource from);

}  // namespace uavsim::common
