// drivers::LogReader and ScanCanalidLog against logs written by LCM's own writer (lcm::LogFile),
// then cut short or damaged byte by byte: every whole event before the damage is delivered, and
// the message names the byte offset of the damaged event (computed here from the event sizes).
#include <gtest/gtest.h>
#include <cerrno>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "drivers/lcm/log_messages.h"
#include "drivers/lcm/log_reader.h"
#include "lcm_test_messages.h"

namespace canalid::drivers {
namespace {

namespace fs = std::filesystem;

struct Written {
  std::string channel;
  std::vector<std::uint8_t> data;
  std::int64_t utime = 0;
  std::uint64_t offset = 0;  // where its event starts: 28 header bytes + channel + data per event
};

fs::path TestPath(const std::string& name) {
  const fs::path dir = fs::path(CANALID_BINARY_DIR) / "test-output" / "lcm_log_reader";
  fs::create_directories(dir);
  fs::remove(dir / name);
  return dir / name;
}

template <class Message>
std::vector<std::uint8_t> Encode(const Message& m) {
  std::vector<std::uint8_t> data(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(data.data(), 0, static_cast<int>(data.size()));
  return data;
}

// Writes `events` with lcm::LogFile and fills in their offsets.
void WriteWithLcm(const fs::path& path, std::vector<Written>& events) {
  lcm::LogFile log(path.string(), "w");
  ASSERT_TRUE(log.good());
  std::uint64_t offset = 0;
  for (std::size_t i = 0; i < events.size(); ++i) {
    Written& w = events[i];
    lcm::LogEvent e;
    e.eventnum = static_cast<std::int64_t>(i);
    e.timestamp = w.utime;
    e.channel = w.channel;
    e.datalen = static_cast<std::int32_t>(w.data.size());
    e.data = w.data.data();
    ASSERT_EQ(log.writeEvent(&e), 0);
    w.offset = offset;
    offset += 28 + w.channel.size() + w.data.size();
  }
}

std::vector<Written> SomeEvents() {
  std::vector<Written> events;
  canalid::config_t config = testing::MakeConfig();
  events.push_back({"CANALID_CONFIG", Encode(config), 1000});
  for (int i = 0; i < 5; ++i)
    events.push_back({"CANALID_SAMPLE_plc1", Encode(testing::MakeSample(i)), 2000 + i});
  events.push_back({"OTHER_CHANNEL", {}, 3000});  // an empty message is legal
  events.push_back({"CANALID_MODEL_pool2", Encode(testing::MakeModel()), 4000});
  return events;
}

std::vector<std::uint8_t> ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void WriteBytes(const fs::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

// Reads to the end of the log; returns how many events came.
std::size_t ReadAll(LogReader& reader) {
  LogEvent e;
  std::size_t read = 0;
  while (reader.Next(&e)) ++read;
  return read;
}

TEST(LcmLogReader, ReadsWhatLcmWroteWithOffsets) {
  const fs::path path = TestPath("whole.lcmlog");
  std::vector<Written> events = SomeEvents();
  WriteWithLcm(path, events);
  LogReader reader(path.string());
  LogEvent e;
  for (std::size_t i = 0; i < events.size(); ++i) {
    ASSERT_TRUE(reader.Next(&e)) << i << ": " << reader.problem();
    EXPECT_EQ(e.event_number, static_cast<std::int64_t>(i));
    EXPECT_EQ(e.utime, events[i].utime);
    EXPECT_EQ(e.offset, events[i].offset);
    EXPECT_EQ(std::string(e.channel), events[i].channel);
    EXPECT_EQ(std::vector<std::uint8_t>(e.data.begin(), e.data.end()), events[i].data);
  }
  EXPECT_FALSE(reader.Next(&e));
  EXPECT_EQ(reader.end(), LogEnd::kClean);
  EXPECT_EQ(reader.problem(), "");
  EXPECT_EQ(reader.position(), fs::file_size(path));
}

// The reader takes the file in chunks of kChunkBytes: events that straddle a chunk's end, and
// one larger than a chunk, come back whole, and then a cut inside the large one is found.
TEST(LcmLogReader, EventsAcrossChunksAndLargerThanAChunkComeBackWhole) {
  const fs::path path = TestPath("chunks.lcmlog");
  std::vector<Written> events;
  std::uint64_t bytes = 0;
  for (std::size_t i = 0; bytes < 6 * LogReader::kChunkBytes; ++i) {
    // Sizes that do not divide the chunk: boundaries fall inside headers, channels and data.
    std::vector<std::uint8_t> data(static_cast<std::size_t>(997 + 13 * (i % 37)));
    for (std::size_t j = 0; j < data.size(); ++j) data[j] = static_cast<std::uint8_t>(i + j);
    if (i == 700) data.assign(LogReader::kChunkBytes * 5 / 2, static_cast<std::uint8_t>(7));
    events.push_back(
        {"CHANNEL_" + std::to_string(i % 11), std::move(data), static_cast<std::int64_t>(i)});
    bytes += 28 + events.back().channel.size() + events.back().data.size();
  }
  WriteWithLcm(path, events);
  {
    LogReader reader(path.string());
    LogEvent e;
    for (std::size_t i = 0; i < events.size(); ++i) {
      ASSERT_TRUE(reader.Next(&e)) << i << ": " << reader.problem();
      ASSERT_EQ(e.offset, events[i].offset) << i;
      ASSERT_EQ(std::string(e.channel), events[i].channel) << i;
      ASSERT_TRUE(
          std::equal(e.data.begin(), e.data.end(), events[i].data.begin(), events[i].data.end()))
          << i;
    }
    EXPECT_FALSE(reader.Next(&e));
    EXPECT_EQ(reader.end(), LogEnd::kClean);
    EXPECT_EQ(reader.position(), bytes);
  }
  // Cut inside the large event's data: the 700 before it, then truncation at its offset.
  std::vector<std::uint8_t> all = ReadBytes(path);
  all.resize(static_cast<std::size_t>(events[700].offset) + 28 + 4000);
  WriteBytes(path, all);
  LogReader reader(path.string());
  EXPECT_EQ(ReadAll(reader), 700U);
  EXPECT_EQ(reader.end(), LogEnd::kTruncated);
  EXPECT_NE(reader.problem().find("byte " + std::to_string(events[700].offset) + ": event 700"),
            std::string::npos)
      << reader.problem();
}

// A log that shrinks while it is read (rotated, or cut by another process): the events read
// stay, and the problem says the file got shorter, not an errno of an earlier call.
TEST(LcmLogReader, AFileThatShrinksWhileReadIsNamedAsSuch) {
  const fs::path path = TestPath("shrinks.lcmlog");
  std::vector<Written> events;
  for (std::size_t i = 0; i < 3; ++i) {
    events.push_back({"CHANNEL", std::vector<std::uint8_t>(LogReader::kChunkBytes * 2 / 3, 1),
                      static_cast<std::int64_t>(i)});
  }
  WriteWithLcm(path, events);
  LogReader reader(path.string());
  LogEvent e;
  ASSERT_TRUE(reader.Next(&e)) << reader.problem();  // the first chunk is read
  fs::resize_file(path, static_cast<std::uintmax_t>(events[1].offset) + 100);
  errno = ENOENT;  // a stale errno must not become the reason
  EXPECT_FALSE(reader.Next(&e));
  EXPECT_EQ(reader.end(), LogEnd::kTruncated);
  // The reader had the first chunk; the file gave nothing after it.
  EXPECT_NE(reader.problem().find("byte " + std::to_string(events[1].offset) +
                                  ": event 1: no bytes after byte " +
                                  std::to_string(LogReader::kChunkBytes) +
                                  ": the file is shorter than when it was opened"),
            std::string::npos)
      << reader.problem();
  EXPECT_EQ(reader.problem().find("No such file"), std::string::npos) << reader.problem();

  // Cut at event 2's start while event 1 is still in the reader's buffer: the two come back,
  // then the end is a truncation, not a clean end.
  const fs::path at_boundary = TestPath("shrinks-at-boundary.lcmlog");
  WriteWithLcm(at_boundary, events);
  LogReader second(at_boundary.string());
  ASSERT_TRUE(second.Next(&e)) << second.problem();
  fs::resize_file(at_boundary, static_cast<std::uintmax_t>(events[2].offset));
  std::size_t more = 0;
  while (second.Next(&e)) ++more;
  EXPECT_EQ(more, 1U);
  EXPECT_EQ(second.end(), LogEnd::kTruncated) << second.problem();
  EXPECT_NE(second.problem().find("byte " + std::to_string(events[2].offset) +
                                  ": no bytes after byte " + std::to_string(events[2].offset) +
                                  ": the file is shorter than when it was opened"),
            std::string::npos)
      << second.problem();
}

TEST(LcmLogReader, EmptyFileIsACleanEmptyLog) {
  const fs::path path = TestPath("empty.lcmlog");
  WriteBytes(path, {});
  LogReader reader(path.string());
  LogEvent e;
  EXPECT_FALSE(reader.Next(&e));
  EXPECT_EQ(reader.end(), LogEnd::kClean);
}

TEST(LcmLogReader, MissingFileIsNamed) {
  try {
    LogReader reader("/nonexistent/run.lcmlog");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/run.lcmlog: cannot open"), std::string::npos)
        << e.what();
  }
}

// Every cut inside the last event (header, channel or data) keeps the events before it.
TEST(LcmLogReader, TruncatedAnywhereInTheLastEventKeepsTheOthers) {
  const fs::path whole = TestPath("whole-for-cuts.lcmlog");
  std::vector<Written> events = SomeEvents();
  WriteWithLcm(whole, events);
  const std::vector<std::uint8_t> bytes = ReadBytes(whole);
  const std::uint64_t last = events.back().offset;
  for (std::uint64_t cut = last + 1; cut < bytes.size(); ++cut) {
    const fs::path path = TestPath("cut.lcmlog");
    WriteBytes(path,
               std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + static_cast<long>(cut)));
    LogReader reader(path.string());
    const std::size_t read = ReadAll(reader);
    ASSERT_EQ(read, events.size() - 1) << "cut at " << cut;
    EXPECT_EQ(reader.end(), LogEnd::kTruncated) << "cut at " << cut;
    EXPECT_EQ(reader.problem().rfind("byte " + std::to_string(last) + ": ", 0), 0U)
        << reader.problem();
    EXPECT_EQ(reader.position(), last);
  }
}

TEST(LcmLogReader, BadSyncWordIsCorruptionAtItsOffset) {
  const fs::path path = TestPath("bad-sync.lcmlog");
  std::vector<Written> events = SomeEvents();
  WriteWithLcm(path, events);
  std::vector<std::uint8_t> bytes = ReadBytes(path);
  bytes[events[3].offset + 1] ^= 0xFF;
  WriteBytes(path, bytes);
  LogReader reader(path.string());
  const std::size_t read = ReadAll(reader);
  EXPECT_EQ(read, 3U);
  EXPECT_EQ(reader.end(), LogEnd::kCorrupt);
  EXPECT_EQ(reader.problem().rfind("byte " + std::to_string(events[3].offset) + ": ", 0), 0U)
      << reader.problem();
  EXPECT_NE(reader.problem().find("sync word"), std::string::npos) << reader.problem();
}

TEST(LcmLogReader, ImpossibleChannelLengthIsCorruption) {
  const fs::path path = TestPath("bad-channel-length.lcmlog");
  std::vector<Written> events = SomeEvents();
  WriteWithLcm(path, events);
  std::vector<std::uint8_t> bytes = ReadBytes(path);
  bytes[events[2].offset + 20] = 0x7F;  // channel length's most significant byte
  WriteBytes(path, bytes);
  LogReader reader(path.string());
  const std::size_t read = ReadAll(reader);
  EXPECT_EQ(read, 2U);
  EXPECT_EQ(reader.end(), LogEnd::kCorrupt);
  EXPECT_NE(reader.problem().find("channel length"), std::string::npos) << reader.problem();
}

class Recorder : public LogMessageVisitor {
 public:
  void OnConfig(const canalid::config_t& c, const LogEvent&) override { configs.push_back(c.text); }
  void OnSample(const std::string& plc, const canalid::sample_t& s, const LogEvent&) override {
    plcs.push_back(plc);
    sequences.push_back(s.sequence);
  }
  void OnModel(const canalid::model_snapshot_t& m, const LogEvent&) override {
    models.push_back(m.reach);
  }
  std::vector<std::string> configs, plcs, models;
  std::vector<std::int64_t> sequences;
};

TEST(LcmLogReader, ScanDeliversOneDaemonsMessagesAndAdoptsItsPrefix) {
  const fs::path path = TestPath("scan.lcmlog");
  std::vector<Written> events;
  events.push_back({"CANALID_SAMPLE_plc1", Encode(testing::MakeSample(7)), 1});  // before config
  std::vector<Written> rest = SomeEvents();
  events.insert(events.end(), rest.begin(), rest.end());
  events.push_back({"OTHERD_SAMPLE_plc1", Encode(testing::MakeSample(9)), 9000});
  WriteWithLcm(path, events);
  Recorder recorder;
  const LogScanResult result = ScanCanalidLog(path.string(), {}, recorder);
  EXPECT_EQ(result.end, LogEnd::kClean);
  EXPECT_EQ(result.prefix, "CANALID_");
  EXPECT_EQ(recorder.configs, std::vector<std::string>{testing::MakeConfig().text});
  EXPECT_EQ(recorder.sequences, (std::vector<std::int64_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(recorder.plcs, std::vector<std::string>(5, "plc1"));
  EXPECT_EQ(recorder.models, std::vector<std::string>{testing::MakeModel().reach});
  EXPECT_EQ(result.samples, 5);
  EXPECT_EQ(result.skipped_events, 3);  // the early sample, OTHER_CHANNEL, the other prefix
}

TEST(LcmLogReader, ScanStopsAtAMessageThatDoesNotDecode) {
  const fs::path path = TestPath("bad-message.lcmlog");
  std::vector<Written> events = SomeEvents();
  events[3].data.resize(events[3].data.size() / 2);  // a sample cut in half, framed as whole
  WriteWithLcm(path, events);
  Recorder recorder;
  const LogScanResult result = ScanCanalidLog(path.string(), {}, recorder);
  EXPECT_EQ(result.end, LogEnd::kCorrupt);
  EXPECT_EQ(recorder.sequences, (std::vector<std::int64_t>{0, 1}));
  EXPECT_NE(result.problem.find("byte " + std::to_string(events[3].offset) +
                                ": event 3 on "
                                "CANALID_SAMPLE_plc1 does not decode as canalid.sample_t"),
            std::string::npos)
      << result.problem;
  EXPECT_EQ(result.bytes, events[3].offset);
}

// lcm-gen's decoder throws std::length_error on a string of length 0 (found by tests/fuzz
// lcm_log): such a message is corrupt like any other that does not decode, not an exception.
TEST(LcmLogReader, ScanReportsAStringOfLengthZeroAsCorrupt) {
  const fs::path path = TestPath("zero-string.lcmlog");
  std::vector<Written> events = SomeEvents();
  canalid::sample_t sample = testing::MakeSample(2);
  sample.source = "";  // encoded as length 1 (the terminator); patched to 0 below
  std::vector<uint8_t> bytes = Encode(sample);
  // utime, sequence (8 bytes each) after the 8-byte hash: the source's length prefix.
  ASSERT_EQ(bytes[24 + 3], 1);
  bytes[24 + 3] = 0;
  events[3].data = bytes;
  WriteWithLcm(path, events);
  Recorder recorder;
  LogScanResult result;
  ASSERT_NO_THROW(result = ScanCanalidLog(path.string(), {}, recorder));
  EXPECT_EQ(result.end, LogEnd::kCorrupt);
  EXPECT_NE(result.problem.find("does not decode as canalid.sample_t"), std::string::npos)
      << result.problem;
  EXPECT_EQ(result.bytes, events[3].offset);
}

}  // namespace
}  // namespace canalid::drivers
