// SIGKILL of cell-program-store while a client streams puts, and of a client in the middle of a chunked
// put (DESIGN §7: a kill -9 at any moment loses no accepted program).
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/program_store/client.h"
#include "cell/program_store/sha256.h"
#include "cell/testing/process.h"
#include "put_stream_content.h"

namespace fs = std::filesystem;
namespace ps = cell::program_store;
using cell::testing::Process;

namespace {

class ProgramStoreCrashTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = cell::testing::MakeTempDir("cell-ps-crash-");
    fs::create_directories(dir_ + "/data");
    bus_ = std::make_unique<cell::bus::Participant>("program_store_crash_test");
    client_ = std::make_unique<ps::Client>(*bus_, cell::bus::Millis(10000));
  }
  void TearDown() override {
    if (HasFailure())
      std::fprintf(stderr, "STORE LOG:\n%s\nSTREAM ERR:\n%s\n", StoreLog().c_str(),
                   cell::testing::ReadFile(dir_ + "/stream.err").c_str());
    client_.reset();
    bus_.reset();
    store_.reset();
    fs::remove_all(dir_);
  }
  void StartStore() {
    ++starts_;
    store_ = std::make_unique<Process>(
        std::vector<std::string>{cell::testing::BinDir() + "/cell-program-store"},
        std::map<std::string, std::string>{{"CELL_DATA_DIR", dir_ + "/data"},
                                           {"CELL_PROGRAM_STORE_STREAM_IDLE_S", "2"}},
        "", dir_ + "/store" + std::to_string(starts_) + ".err");
    // Ready when a listing is answered (bounded).
    bool ready = cell::bus::WaitUntil(
        [&] {
          try {
            client_->List("HOST", "*");
            return true;
          } catch (const cell::Error&) {
            return !store_->Running();
          }
        },
        std::chrono::seconds(30));
    ASSERT_TRUE(ready && store_->Running()) << StoreLog();
  }
  std::string StoreLog() {
    return cell::testing::ReadFile(dir_ + "/store" + std::to_string(starts_) + ".err");
  }
  std::map<std::string, std::string> Acks(const std::string& out) {
    std::map<std::string, std::string> acks;
    std::istringstream in(cell::testing::ReadFile(out));
    std::string tag, name, sha;
    while (in >> tag >> name >> sha)
      if (tag == "ACK" && sha.size() == 64) acks[name] = sha;
    return acks;
  }
  size_t ScratchFiles() {
    fs::path d = fs::path(dir_) / "data" / "program-store-streams";
    if (!fs::exists(d)) return 0;
    return static_cast<size_t>(std::distance(fs::directory_iterator(d), fs::directory_iterator()));
  }

  std::string dir_;
  int starts_ = 0;
  std::unique_ptr<Process> store_;
  std::unique_ptr<cell::bus::Participant> bus_;
  std::unique_ptr<ps::Client> client_;
};

TEST_F(ProgramStoreCrashTest, KilledStoreKeepsEveryAcknowledgedPutAndNoPartialOne) {
  StartStore();
  const size_t kSize = 4096;
  std::string out = dir_ + "/stream.out";
  Process writer({cell::testing::BinDir() + "/program_store_put_stream", "--count", "100000", "--size",
                  std::to_string(kSize)},
                 {}, out, dir_ + "/stream.err");
  auto wait_acks = [&](size_t n) {
    return cell::bus::WaitUntil([&] { return Acks(out).size() >= n || !writer.Running(); },
                                std::chrono::seconds(30));
  };
  for (size_t kill_after : {25u, 60u}) {
    ASSERT_TRUE(wait_acks(kill_after));
    ASSERT_TRUE(writer.Running()) << cell::testing::ReadFile(dir_ + "/stream.err");
    store_->Signal(SIGKILL);
    ASSERT_TRUE(store_->Wait(std::chrono::seconds(5)).has_value());
    size_t acked_at_kill = Acks(out).size();
    StartStore();
    // The writer retries its in-flight put with the same idempotency key and carries on.
    ASSERT_TRUE(wait_acks(acked_at_kill + 10)) << cell::testing::ReadFile(dir_ + "/stream.err");
  }
  writer.Signal(SIGKILL);
  writer.Wait(std::chrono::seconds(5));

  std::map<std::string, std::string> acks = Acks(out);
  nlohmann::json ls = client_->List("HOST", "S*");
  std::map<std::string, nlohmann::json> stored;
  for (auto& f : ls) stored[f["name"]] = f;
  // Every acknowledged put is there, once (revision 1: a retry never ran twice), with its content.
  for (auto& [name, sha] : acks) {
    ASSERT_TRUE(stored.count(name)) << name << " was acknowledged but is missing";
    EXPECT_EQ(stored[name]["revision"], 1) << name;
    auto content = client_->Get("HOST", name);
    ASSERT_TRUE(content.has_value()) << name;
    EXPECT_EQ(ps::Sha256Hex(*content), sha) << name;
  }
  // Beyond them at most the put in flight when the writer died, and then whole.
  size_t extra = 0;
  for (auto& [name, f] : stored) {
    if (acks.count(name)) continue;
    ++extra;
    auto content = client_->Get("HOST", name);
    ASSERT_TRUE(content.has_value()) << name;
    EXPECT_EQ(*content, cell::testing::StreamContent(name, kSize)) << name << " is partial";
  }
  EXPECT_LE(extra, 1u);
  EXPECT_EQ(stored.size(), acks.size() + extra);
  EXPECT_GE(acks.size(), 70u);
}

TEST_F(ProgramStoreCrashTest, ClientKilledMidChunkedPutLeavesStoreUnchanged) {
  StartStore();
  ps::Client::PutOptions o;
  client_->Put("BEFORE", "data that was there before\n", o);
  nlohmann::json before = client_->List("HOST", "*");

  std::string out = dir_ + "/big.out";
  Process big({cell::testing::BinDir() + "/program_store_put_stream", "--big", "HALF DONE", "--size",
               std::to_string(8u << 20), "--chunk-delay-ms", "20"},
              {}, out, dir_ + "/big.err");
  ASSERT_TRUE(cell::bus::WaitUntil(
      [&] { return cell::testing::ReadFile(out).find("CHUNK 10\n") != std::string::npos || !big.Running(); },
      std::chrono::seconds(30)));
  ASSERT_TRUE(big.Running()) << cell::testing::ReadFile(dir_ + "/big.err");
  big.Signal(SIGKILL);
  big.Wait(std::chrono::seconds(5));
  EXPECT_EQ(cell::testing::ReadFile(out).find("DONE"), std::string::npos);
  EXPECT_EQ(ScratchFiles(), 1u);  // staged, not visible
  EXPECT_EQ(client_->List("HOST", "*"), before);

  // The abandoned stream expires (idle limit 2 s here) and its scratch file goes.
  ASSERT_TRUE(cell::bus::WaitUntil([&] { return ScratchFiles() == 0; }, std::chrono::seconds(15)))
      << StoreLog();
  // The store logs the expiry after removing the file: wait for the line too.
  EXPECT_TRUE(
      cell::bus::WaitUntil([&] { return StoreLog().find("abandoned upload stream") != std::string::npos; },
                           std::chrono::seconds(5)))
      << StoreLog();
  EXPECT_EQ(client_->List("HOST", "*"), before);
  EXPECT_FALSE(client_->Get("HOST", "HALF DONE").has_value());
  // And the store still takes a large put.
  std::string again = cell::testing::StreamContent("HALF DONE", 1u << 20);
  client_->Put("HALF DONE", again, o);
  EXPECT_EQ(client_->Get("HOST", "HALF DONE"), again);
}

}  // namespace
