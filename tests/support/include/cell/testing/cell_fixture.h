// A GoogleTest fixture around a LocalCell for multi-process tests: the test's SetUp calls Up(stations), the
// cell goes down (`cellctl down`) after every test, pass or fail, and Ctl/CtlJson run cellctl against it.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/testing/local_cell.h"

namespace cell::testing {

class CellFixture : public ::testing::Test {
 protected:
  // `prefix` names the cell's temporary data dir (kept with CELL_TEST_KEEP=1).
  explicit CellFixture(const std::string& prefix = "cell-test-") : cell_(prefix) {}

  // `cellctl up --stations S --clock C`; a failure ends the test (call from SetUp, then check HasFatalFailure
  // or use ASSERT_NO_FATAL_FAILURE).
  void Up(const std::string& stations, const std::string& clock = "virtual") {
    auto r = cell_.Up(stations, clock);
    ASSERT_EQ(r.code, 0) << r.out << r.err;
  }
  void TearDown() override {
    if (cell_.is_up()) {
      auto r = cell_.Down();
      EXPECT_EQ(r.code, 0) << r.err;
    }
  }
  RunResult Ctl(std::vector<std::string> args) { return cell_.Ctl(std::move(args)); }
  nlohmann::json CtlJson(std::vector<std::string> args) { return cell_.Json(std::move(args)); }

  LocalCell cell_;
};

}  // namespace cell::testing
