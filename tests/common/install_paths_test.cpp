// Where a built or installed program finds the shipped models: an explicit option, then the
// environment, then PREFIX/share/uavsim/models beside PREFIX/bin, then the source tree.
#include "uavsim/common/install_paths.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace uavsim::common {
namespace {

namespace fs = std::filesystem;

// PREFIX/bin and PREFIX/share/uavsim/models/worlds, and a source tree's models/worlds, under a
// fresh folder of this test process's temporary directory
class ModelsDirSearchTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::path(::testing::TempDir()) /
            ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(root_);
    bin_ = root_ / "prefix/bin";
    installed_ = root_ / "prefix/share/uavsim/models";
    source_ = root_ / "src/models";
    fs::create_directories(bin_);
    fs::create_directories(installed_ / "worlds");
    fs::create_directories(source_ / "worlds");
  }
  void TearDown() override { fs::remove_all(root_); }

  ModelsDirSearch search() const {
    ModelsDirSearch s;
    s.executable_dir = bin_.string();
    s.source_tree = source_.string();
    return s;
  }

  fs::path root_, bin_, installed_, source_;
};

TEST_F(ModelsDirSearchTest, AnInstalledProgramFindsTheModelsOfItsPrefixBeforeTheSourceTree) {
  const ModelsDir d = find_models_dir(search());
  EXPECT_EQ(d.from, ModelsDirSource::kInstall);
  EXPECT_EQ(fs::path(d.path), installed_.lexically_normal());
}

TEST_F(ModelsDirSearchTest, ABuiltProgramFallsBackToTheSourceTree) {
  // a build folder: no share/ beside it
  ModelsDirSearch s = search();
  s.executable_dir = (root_ / "build/server").string();
  const ModelsDir d = find_models_dir(s);
  EXPECT_EQ(d.from, ModelsDirSource::kSourceTree);
  EXPECT_EQ(d.path, source_.string());
}

TEST_F(ModelsDirSearchTest, AnInstallWithoutWorldsIsNotTaken) {
  fs::remove_all(installed_ / "worlds");
  EXPECT_EQ(find_models_dir(search()).from, ModelsDirSource::kSourceTree);
}

TEST_F(ModelsDirSearchTest, TheEnvironmentComesBeforeTheInstallAndTheOptionBeforeBoth) {
  ModelsDirSearch s = search();
  s.environment = (root_ / "env_models").string();
  ModelsDir d = find_models_dir(s);
  EXPECT_EQ(d.from, ModelsDirSource::kEnvironment);
  // taken as given even though it does not exist: the caller's error names it
  EXPECT_EQ(d.path, s.environment);
  s.option = (root_ / "option_models").string();
  d = find_models_dir(s);
  EXPECT_EQ(d.from, ModelsDirSource::kOption);
  EXPECT_EQ(d.path, s.option);
}

TEST_F(ModelsDirSearchTest, NothingFoundNamesTheInstallLocation) {
  fs::remove_all(installed_ / "worlds");
  fs::remove_all(source_ / "worlds");
  const ModelsDir d = find_models_dir(search());
  EXPECT_EQ(d.from, ModelsDirSource::kNone);
  EXPECT_EQ(fs::path(d.path), installed_.lexically_normal());
  EXPECT_STREQ(to_string(d.from), "none");
}

TEST(ExecutableDir, IsTheFolderOfThisTestProgram) {
  const std::string dir = executable_dir();
  ASSERT_FALSE(dir.empty());
  EXPECT_TRUE(fs::is_directory(dir));
  // a program beside this one is found there; a missing one falls back to the built path
  EXPECT_EQ(installed_or_built_program("no-such-uavsim-program", "/built/path"), "/built/path");
  const fs::path self = fs::read_symlink("/proc/self/exe");
  EXPECT_EQ(installed_or_built_program(self.filename().string(), "/built/path"), self.string());
}

}  // namespace
}  // namespace uavsim::common
