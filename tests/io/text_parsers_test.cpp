// The text parsers behind the sequence and calibration readers (src/io/text_parsers.h), on
// inputs that broke the rule the fuzz targets (fuzz/) check: bad input is an
// ssta::Error naming the file and line, never another exception, a crash or undefined
// behaviour.

#include "io/text_parsers.h"

#include <string>

#include <gtest/gtest.h>

#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

/// Runs `parse`, expects ssta::Error, returns its message.
template <typename Parse>
std::string ErrorOf(Parse&& parse) {
  try {
    parse();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ssta::Error";
  return "";
}

TEST(ParseKittiTimestamps, ReadsNineFractionDigitsExactly) {
  const auto t = ParseKittiTimestamps("2011-09-26 13:02:25.964389445\n2011-09-26 13:02:26\n", "ts.txt");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t[0], 1317042145964389445LL);
  EXPECT_EQ(t[1] - t[0], 35610555LL);
}

TEST(ParseKittiTimestamps, ALetterInTheFractionIsAnErrorNamingTheLine) {
  // Used to escape as std::invalid_argument (std::stoll on the fraction digits).
  const std::string m = ErrorOf([] { ParseKittiTimestamps("2011-09-26 13:02:25.1\n2011-09-26 13:02:25.x\n", "ts.txt"); });
  EXPECT_NE(m.find("ts.txt:2: bad timestamp"), std::string::npos) << m;
}

TEST(ParseKittiTimestamps, OutOfRangeFieldsAreErrorsNotOverflows) {
  // A huge year used to overflow int arithmetic and 'nan' seconds were cast to an integer
  // (undefined behaviour).
  for (const char* line : {"-2147483648-01-01 00:00:00", "2011-13-01 00:00:00", "2011-01-01 00:00:nan",
                           "99999999999-01-01 00:00:00", "2011-01-01 00:00:00.", "2011-01-01 00:00:00 junk"}) {
    const std::string m = ErrorOf([&] { ParseKittiTimestamps(std::string(line) + "\n", "ts.txt"); });
    EXPECT_NE(m.find("ts.txt:1: bad timestamp"), std::string::npos) << line << ": " << m;
  }
}

TEST(ParseOxtsRow, APoleLatitudeIsAnError) {
  // The Mercator projection is infinite at the poles.
  const std::string m = ErrorOf([] { ParseOxtsRow("90 8 110 0 0 0\n", "oxts/0.txt"); });
  EXPECT_NE(m.find("oxts/0.txt: latitude"), std::string::npos) << m;
  EXPECT_EQ(ParseOxtsRow("49 8 110 0.01 -0.02 0.1 7\n", "oxts/0.txt").size(), 7u);
}

TEST(ParseAslPoseCsv, AQuaternionTooLargeToNormaliseIsAnError) {
  const std::string m = ErrorOf([] { ParseAslPoseCsv("#h\n1,0,0,0,1e200,1e200,1e200,1e200\n", "pose0/data.csv"); });
  EXPECT_NE(m.find("pose0/data.csv:2: quaternion"), std::string::npos) << m;
}

TEST(ParseAslPoseCsv, TheColumnCountComesFromTheFirstDataRow) {
  // Comment lines before the data do not count as the first row.
  const auto poses = ParseAslPoseCsv("#a\n#b\n\n1,1,2,3,1,0,0,0,9,9\n2,1,2,3,0,0,0,1.001,9,9\n", "gt.csv");
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_DOUBLE_EQ(poses[1].world_q_body.z(), 1.0);
  const std::string m = ErrorOf([] { ParseAslPoseCsv("#a\n1,2,3\n", "p.csv"); });
  EXPECT_NE(m.find("p.csv:2: expected at least 8 columns"), std::string::npos) << m;
}

TEST(ParseAslImageList, AnEmptyFileNameIsAnErrorNamingTheLine) {
  const std::string m = ErrorOf([] { ParseAslImageList("#t,f\n1,a.png\n2,\n", "cam0/data.csv"); });
  EXPECT_NE(m.find("cam0/data.csv:3: empty file name"), std::string::npos) << m;
}

TEST(ParseCameraCalibration, AKeyThatIsNotANameIsAnError) {
  // A complex YAML key ("? [a, b]") used to escape RejectUnknownKeys as
  // YAML::TypedBadConversion.
  const std::string m = ErrorOf([] {
    ParseCameraCalibration(
        "T_BS:\n  data: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\nresolution: [64, 48]\nintrinsics: [50, 50, 32, 24]\n"
        "? [a, b]\n: 3\n",
        "cam0/sensor.yaml");
  });
  EXPECT_NE(m.find("cam0/sensor.yaml: top level: keys must be plain names"), std::string::npos) << m;
}

}  // namespace
}  // namespace ssta::internal
