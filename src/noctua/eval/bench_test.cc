#include "noctua/eval/bench.h"

#include <gtest/gtest.h>

#include <string>

#include "noctua/util/error.h"

namespace noctua::eval {
namespace {

TEST(BenchSamplesTest, MedianOverAllAndRangeOfPerRepetitionMedians) {
  BenchSamples samples;
  for (double ms : {1.0, 2.0, 3.0}) samples.Add(0, ms);
  for (double ms : {5.0, 6.0, 7.0}) samples.Add(1, ms);
  EXPECT_EQ(samples.count(), 6u);
  EXPECT_DOUBLE_EQ(samples.RepetitionMedianRange().first, 2.0);
  EXPECT_DOUBLE_EQ(samples.RepetitionMedianRange().second, 6.0);
  const double median = samples.Median();
  EXPECT_GE(median, 3.0);
  EXPECT_LE(median, 5.0);
}

TEST(BenchTableTest, RowsKeepTheOrderTheyWereFirstNamed) {
  BenchTable table;
  table.Get("method", "orb", "x").ms.Add(0, 1.0);
  table.Get("stage", "fast", "y").ms.Add(0, 2.0);
  table.Get("method", "orb", "x").ms.Add(0, 3.0);
  ASSERT_EQ(table.rows().size(), 2u);
  EXPECT_EQ(table.rows()[0].name, "orb");
  EXPECT_EQ(table.rows()[0].ms.count(), 2u);
  EXPECT_EQ(table.rows()[1].group, "stage");
}

TEST(BenchReportTest, RatiosAreToTheReferenceMedian) {
  BenchResult result;
  result.options.dataset = "seq";
  result.frames = 2;
  for (double ms : {4.0, 4.0, 4.0}) result.reference_ms.Add(0, ms);
  BenchRow& method = result.table.Get("method", "paper", "end to end");
  for (double ms : {8.0, 8.0, 8.0}) method.ms.Add(0, ms);
  method.keypoints = {900.0, 1000.0, 1100.0};
  result.table.Get("stage", "oFAST", "timer").ms.Add(0, 1.0);
  const BenchReport report = MakeBenchReport(result);
  EXPECT_DOUBLE_EQ(report.json["reference"]["median_ms"].get<double>(), 4.0);
  EXPECT_DOUBLE_EQ(report.json["methods"][0]["ratio_to_orb_opencv"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(report.json["methods"][0]["frames_per_s"].get<double>(), 125.0);
  EXPECT_DOUBLE_EQ(report.json["methods"][0]["keypoints_median"].get<double>(), 1000.0);
  EXPECT_DOUBLE_EQ(report.json["stages"][0]["ratio_to_orb_opencv"].get<double>(), 0.25);
  EXPECT_NE(report.markdown.find("| paper | 8.00 | 8.00-8.00 | 2.00 | 125.0 | 1000 |"),
            std::string::npos);
  EXPECT_EQ(report.plot_data,
            "# method median_ms spread_min_ms spread_max_ms\n\"paper\" 8.0000 8.0000 8.0000\n");
}

TEST(BenchReportTest, ANoTimeReferenceIsAnError) {
  BenchResult result;
  result.reference_ms.Add(0, 0.0);
  EXPECT_THROW(MakeBenchReport(result), Error);
}

TEST(CountRatioTestMatchesTest, KeepsOnlyDistinctNearestNeighbours) {
  // Query 0 equals train 0 (distance 0) and is far from train 1: kept. Query 1 is equally far
  // from both trains: refused by the ratio test.
  cv::Mat train = cv::Mat::zeros(2, 32, CV_8U);
  train.row(1).setTo(0xFF);
  cv::Mat query = cv::Mat::zeros(2, 32, CV_8U);
  query.row(1).colRange(0, 16).setTo(0xFF);
  EXPECT_EQ(CountRatioTestMatches(query, train, 0.8F), 1u);
}

TEST(BenchOptionsTest, CheckNamesTheField) {
  BenchOptions options;
  options.dataset = "seq";
  options.config = "config/tum_fr1.yaml";
  EXPECT_NO_THROW(options.Check());
  options.frames = 1;
  EXPECT_THROW(options.Check(), Error);
}

}  // namespace
}  // namespace noctua::eval
