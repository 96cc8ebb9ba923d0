// ProgramText: a mapped program reads the same as the file, stays readable after its pages are released,
// and bad paths give clear errors.
#include "cell/interp/program_text.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "cell/error/error.h"

namespace cell::interp {
namespace {

std::string TempFile(const std::string& content) {
  std::string path =
      (std::filesystem::temp_directory_path() /
       ("program_text_test_" + std::to_string(::getpid()) + "_" + std::to_string(content.size())))
          .string();
  std::ofstream(path, std::ios::binary) << content;
  return path;
}

TEST(ProgramText, MappedFileReadsLikeTheFileAndSurvivesRelease) {
  std::string content;
  for (int i = 0; i < 100000; ++i) content += "N" + std::to_string(i) + " G01 X1. Y2.\n";
  std::string path = TempFile(content);
  auto t = ProgramText::MapFile(path);
  std::filesystem::remove(path);  // the mapping keeps the data
  ASSERT_EQ(t->view().size(), content.size());
  EXPECT_EQ(t->view(), content);
  t->Release(0, content.size() / 2);
  t->Release(17, 5);              // an empty or reversed range is harmless
  EXPECT_EQ(t->view(), content);  // released pages fault back in with the same bytes
}

TEST(ProgramText, EmptyFileAndOwnedString) {
  std::string path = TempFile("");
  auto t = ProgramText::MapFile(path);
  std::filesystem::remove(path);
  EXPECT_TRUE(t->view().empty());
  auto s = ProgramText::FromString("G0 X1.\n");
  s->Release(0, 100);
  EXPECT_EQ(s->view(), "G0 X1.\n");
}

TEST(ProgramText, MissingFileAndDirectoryAreErrors) {
  try {
    ProgramText::MapFile("/nonexistent/PUMP341");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kNotFound);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/PUMP341"), std::string::npos);
  }
  EXPECT_THROW(ProgramText::MapFile(std::filesystem::temp_directory_path().string()), Error);
}

}  // namespace
}  // namespace cell::interp
