// Vocabulary tree, TF-IDF scoring, the inverted-index database and the vocabulary file.
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include "TestFiles.hpp"
#include "groundslam/bow/BowDatabase.hpp"
#include "groundslam/bow/Vocabulary.hpp"
#include "groundslam/io/Files.hpp"
#include "groundslam/io/VocabularyFile.hpp"

using namespace groundslam;
using groundslam::testing::inputErrorOf;
using groundslam::testing::scratchDir;

namespace {

/// Descriptors scattered around `centres` random prototypes, `noise_bits` bits flipped each.
struct Clusters {
  std::vector<cv::Mat> prototypes;  ///< one 1x32 row each
  cv::Mat around(int prototype, int count, int noise_bits, std::mt19937& rng) const {
    cv::Mat out;
    std::uniform_int_distribution<int> bit(0, 255);
    for (int i = 0; i < count; ++i) {
      cv::Mat d = prototypes[static_cast<size_t>(prototype)].clone();
      for (int b = 0; b < noise_bits; ++b) {
        const int k = bit(rng);
        d.at<unsigned char>(0, k / 8) = static_cast<unsigned char>(d.at<unsigned char>(0, k / 8) ^ (1 << (k % 8)));
      }
      out.push_back(d);
    }
    return out;
  }
};

Clusters makeClusters(int n, unsigned seed) {
  Clusters c;
  cv::RNG rng(seed);
  for (int i = 0; i < n; ++i) {
    cv::Mat d(1, 32, CV_8U);
    rng.fill(d, cv::RNG::UNIFORM, 0, 256);
    c.prototypes.push_back(d);
  }
  return c;
}

/// Training "images": image i holds descriptors of prototypes i, i+1, i+2 (mod n).
std::vector<cv::Mat> trainingImages(const Clusters& c, std::mt19937& rng) {
  std::vector<cv::Mat> images;
  const int n = static_cast<int>(c.prototypes.size());
  for (int i = 0; i < n; ++i) {
    cv::Mat image;
    for (int k = 0; k < 3; ++k) image.push_back(c.around((i + k) % n, 20, 8, rng));
    images.push_back(image);
  }
  return images;
}

}  // namespace

TEST(Vocabulary, ClustersOfDescriptorsBecomeWords) {
  std::mt19937 rng(1);
  const Clusters clusters = makeClusters(16, 3);
  const Vocabulary vocabulary = Vocabulary::train(trainingImages(clusters, rng), {4, 2, 10, 7});
  EXPECT_LE(vocabulary.wordCount(), 16);
  EXPECT_GE(vocabulary.wordCount(), 12);
  // Noisy copies of one prototype share its word; different prototypes mostly get different words.
  int consistent = 0, distinct = 0;
  for (int p = 0; p < 16; ++p) {
    const cv::Mat copies = clusters.around(p, 10, 8, rng);
    const int word = vocabulary.wordOf(copies.ptr<std::uint8_t>(0));
    for (int r = 1; r < 10; ++r) consistent += vocabulary.wordOf(copies.ptr<std::uint8_t>(r)) == word ? 1 : 0;
    distinct += vocabulary.wordOf(clusters.prototypes[static_cast<size_t>((p + 1) % 16)].ptr<std::uint8_t>(0)) != word ? 1 : 0;
  }
  EXPECT_GE(consistent, 16 * 9 - 3);  // a copy 8 bits off its prototype may cross a cluster border
  EXPECT_GE(distinct, 14);
}

TEST(Vocabulary, ScoresAreOneForTheSameImageAndZeroForDisjointOnes) {
  std::mt19937 rng(2);
  const Clusters clusters = makeClusters(16, 5);
  const Vocabulary vocabulary = Vocabulary::train(trainingImages(clusters, rng), {4, 2, 10, 7});
  const BowVector a = vocabulary.transform(clusters.around(0, 30, 6, rng));
  const BowVector a_again = vocabulary.transform(clusters.around(0, 30, 6, rng));
  const BowVector b = vocabulary.transform(clusters.around(8, 30, 6, rng));
  double total = 0.0;
  for (const auto& [word, weight] : a) total += weight;
  EXPECT_NEAR(total, 1.0, 1e-12);  // L1-normalised
  EXPECT_NEAR(bowScore(a, a), 1.0, 1e-12);
  EXPECT_NEAR(bowScore(a, a_again), 1.0, 1e-12);
  EXPECT_NEAR(bowScore(a, b), 0.0, 1e-12);
  // Half the words shared: score 0.5.
  cv::Mat half = clusters.around(0, 15, 6, rng);
  half.push_back(clusters.around(8, 15, 6, rng));
  EXPECT_NEAR(bowScore(a, vocabulary.transform(half)), 0.5, 0.05);
}

TEST(BowDatabase, QueryRanksTheMostSimilarFrameFirst) {
  std::mt19937 rng(3);
  const Clusters clusters = makeClusters(32, 9);
  const Vocabulary vocabulary = Vocabulary::train(trainingImages(clusters, rng), {4, 3, 10, 7});
  BowDatabase database;
  for (int frame = 0; frame < 30; ++frame) {
    cv::Mat image = clusters.around(frame, 20, 6, rng);
    image.push_back(clusters.around(frame + 1, 20, 6, rng));
    database.add(frame, vocabulary.transform(image));
  }
  cv::Mat query = clusters.around(17, 20, 6, rng);
  query.push_back(clusters.around(18, 20, 6, rng));
  const auto results = database.query(vocabulary.transform(query), 3);
  ASSERT_EQ(results.size(), 3u);
  EXPECT_EQ(results[0].frame, 17);
  EXPECT_GT(results[0].score, 0.8);
  EXPECT_GT(results[0].score, results[1].score);
  // Frames 16 and 18 share one of the two words.
  EXPECT_TRUE((results[1].frame == 16 && results[2].frame == 18) || (results[1].frame == 18 && results[2].frame == 16));
  EXPECT_NEAR(results[1].score, 0.5, 0.1);
  EXPECT_NEAR(results[1].score, bowScore(vocabulary.transform(query), vocabulary.transform(query)) * 0.5, 0.1);
}

TEST(VocabularyFile, RoundTripsExactly) {
  const auto dir = scratchDir();
  std::mt19937 rng(4);
  const Clusters clusters = makeClusters(16, 11);
  const Vocabulary vocabulary = Vocabulary::train(trainingImages(clusters, rng), {4, 2, 10, 7});
  writeVocabulary((dir / "v.gslmvoc").string(), vocabulary);
  const Vocabulary back = readVocabulary((dir / "v.gslmvoc").string());
  ASSERT_EQ(back.nodes().size(), vocabulary.nodes().size());
  EXPECT_EQ(back.idf(), vocabulary.idf());
  for (size_t i = 0; i < back.nodes().size(); ++i) {
    EXPECT_EQ(back.nodes()[i].centre, vocabulary.nodes()[i].centre);
    EXPECT_EQ(back.nodes()[i].word, vocabulary.nodes()[i].word);
  }
  const cv::Mat probe = clusters.around(3, 50, 10, rng);
  EXPECT_EQ(back.transform(probe), vocabulary.transform(probe));
}

TEST(VocabularyFile, CorruptTruncatedAndForeignFilesAreNamed) {
  const auto dir = scratchDir();
  std::mt19937 rng(5);
  const Vocabulary vocabulary = Vocabulary::train(trainingImages(makeClusters(16, 13), rng), {4, 2, 10, 7});
  const std::string path = (dir / "v.gslmvoc").string();
  writeVocabulary(path, vocabulary);
  std::string bytes = readTextFile(path);

  std::string flipped = bytes;
  flipped[100] = static_cast<char>(flipped[100] ^ 0x10);
  std::ofstream((dir / "flipped.gslmvoc").string(), std::ios::binary) << flipped;
  EXPECT_NE(inputErrorOf([&] { readVocabulary((dir / "flipped.gslmvoc").string()); }).find("flipped.gslmvoc: vocabulary file is corrupt"),
            std::string::npos);

  std::ofstream((dir / "short.gslmvoc").string(), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  EXPECT_NE(inputErrorOf([&] { readVocabulary((dir / "short.gslmvoc").string()); }).find("truncated or corrupt"), std::string::npos);

  std::string future = bytes;
  future[8] = 7;  // the version field follows the 8-byte magic
  std::ofstream((dir / "future.gslmvoc").string(), std::ios::binary) << future;
  EXPECT_NE(inputErrorOf([&] { readVocabulary((dir / "future.gslmvoc").string()); }).find("format version 7"), std::string::npos);

  std::ofstream((dir / "text.gslmvoc").string()) << "hello";
  EXPECT_NE(inputErrorOf([&] { readVocabulary((dir / "text.gslmvoc").string()); }).find("bad magic"), std::string::npos);
  EXPECT_NE(inputErrorOf([&] { readVocabulary((dir / "missing.gslmvoc").string()); }).find("missing.gslmvoc"), std::string::npos);
}

TEST(VocabularyFile, ShippedVocabularyLoads) {
  const Vocabulary shipped = readVocabulary(std::string(GROUNDSLAM_SOURCE_DIR) + "/config/vocabulary/ground.gslmvoc");
  EXPECT_EQ(shipped.branching(), 10);
  EXPECT_EQ(shipped.depth(), 4);
  EXPECT_GT(shipped.wordCount(), 5000);
}
