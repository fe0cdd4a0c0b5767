#include "firmware/tools/shared_dir.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <string>

namespace qnav::tools {
namespace {

// Sets $QNAV_SHARED_DIR for one test and puts the previous value back.
class SharedDirEnv {
 public:
  explicit SharedDirEnv(const std::string& value) {
    const char* old = std::getenv("QNAV_SHARED_DIR");
    had_ = old != nullptr;
    if (had_) old_ = old;
    ::setenv("QNAV_SHARED_DIR", value.c_str(), 1);
  }
  ~SharedDirEnv() {
    if (had_) {
      ::setenv("QNAV_SHARED_DIR", old_.c_str(), 1);
    } else {
      ::unsetenv("QNAV_SHARED_DIR");
    }
  }

 private:
  bool had_ = false;
  std::string old_;
};

TEST(SharedDir, EnvironmentWinsWhenItHoldsData) {
  const std::string dir = ::testing::TempDir() + "/qnav_shared_env";
  ::mkdir(dir.c_str(), 0755);
  ::mkdir((dir + "/data").c_str(), 0755);
  SharedDirEnv env(dir);
  EXPECT_EQ(shared_dir(), dir);
  EXPECT_EQ(shared_dir_missing(), "");
}

TEST(SharedDir, EnvironmentWithoutDataFallsBackToTheCompiledPath) {
  const std::string dir = ::testing::TempDir() + "/qnav_shared_empty";
  ::mkdir(dir.c_str(), 0755);
  SharedDirEnv env(dir);
  if (holds_shared_data(kCompiledSharedDir)) {
    EXPECT_EQ(shared_dir(), kCompiledSharedDir);
    EXPECT_EQ(shared_dir_missing(), "");
  } else {
    // Neither holds data/: the asked-for folder is kept, and the message names both places.
    EXPECT_EQ(shared_dir(), dir);
    const std::string why = shared_dir_missing();
    EXPECT_NE(why.find(dir), std::string::npos) << why;
    EXPECT_NE(why.find(kCompiledSharedDir), std::string::npos) << why;
    EXPECT_NE(why.find("QNAV_SHARED_DIR"), std::string::npos) << why;
  }
}

}  // namespace
}  // namespace qnav::tools
