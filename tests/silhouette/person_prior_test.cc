// The person prior for cameras without a plate (silhouette/person_prior.h): the person's region
// (segmentation and limbs), masks kept within reach of it, and the capture-wide pool of
// segmenters with its kept regions, driven by a stand-in segmenter that speaks segment.js's
// protocol.

#include "silhouette/person_prior.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "core/cv_interop.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace confluent {
namespace {
namespace fs = std::filesystem;

std::uint8_t At(const Image& image, int x, int y) { return image.data[static_cast<std::size_t>(y) * image.width + x]; }

// A person standing in a 100x200 image: a 20x160 body, certain in its middle, and a left arm
// (shoulder, elbow, wrist) held out sideways that the segmentation lost; the right arm's
// landmarks are unsure.
PersonSegmentation StandingPerson() {
  PersonSegmentation person;
  person.probability = Image(100, 200, 1);
  cv::Mat probability = AsCvMat(person.probability);
  probability(cv::Rect(40, 20, 20, 160)).setTo(150);
  probability(cv::Rect(45, 30, 10, 140)).setTo(250);
  cv::compare(probability, 127, AsCvMat(person.mask = Image(100, 200, 1)), cv::CMP_GT);
  person.presence = 1;
  person.landmarks[11] = {55, 40, 1};
  person.landmarks[13] = {75, 40, 1};
  person.landmarks[15] = {92, 40, 1};
  person.landmarks[12] = {45, 40, 0.2f};
  person.landmarks[14] = {10, 40, 0.2f};
  return person;
}

TEST(PersonPrior, RegionHoldsTheSegmentationAndTheLimbsTheLandmarksAreSureOf) {
  PersonPriorOptions options;
  const PersonRegion region = MakePersonRegion(StandingPerson(), options);
  ASSERT_FALSE(region.region.empty());
  EXPECT_DOUBLE_EQ(region.height_px, 160);
  EXPECT_EQ(At(region.region, 50, 100), 255);  // the body
  EXPECT_EQ(At(region.region, 75, 40), 255);   // the elbow and the wrist of the lost arm
  EXPECT_EQ(At(region.region, 92, 40), 255);
  EXPECT_EQ(At(region.region, 10, 40), 0);     // the unsure arm is not drawn
  EXPECT_EQ(At(region.region, 75, 100), 0);    // beside the body
  // The core: where the probability passes core_probability (0.9 = 229.5), inside the body only.
  EXPECT_EQ(At(region.core, 50, 100), 255);
  EXPECT_EQ(At(region.core, 42, 100), 0);
  EXPECT_EQ(At(region.core, 75, 40), 0);
  // Nobody found: no region.
  PersonSegmentation nobody = StandingPerson();
  AsCvMat(nobody.mask).setTo(0);
  EXPECT_TRUE(MakePersonRegion(nobody, options).region.empty());
}

TEST(PersonPrior, MasksKeepWhatLiesWithinReachOfThePersonOrInTheOthersHullOnly) {
  PersonPriorOptions options;
  options.reach = 0.05;  // 8 pixels for the 160-pixel person
  const PersonRegion region = MakePersonRegion(StandingPerson(), options);
  Image mask(100, 200, 1);
  cv::Mat m = AsCvMat(mask);
  m(cv::Rect(40, 20, 20, 160)).setTo(255);  // the body
  m(cv::Rect(60, 100, 6, 20)).setTo(255);   // a rim 6 pixels wide beside it (a shadow, a loose shirt)
  m(cv::Rect(80, 150, 15, 15)).setTo(255);  // a ghost of the room 20 pixels away
  const Image kept = KeepNearPerson(mask, region);
  const cv::Mat k = AsCvMat(kept);
  EXPECT_EQ(cv::countNonZero(k(cv::Rect(40, 20, 20, 160))), 20 * 160);
  EXPECT_EQ(cv::countNonZero(k(cv::Rect(60, 100, 6, 20))), 6 * 20);
  EXPECT_EQ(cv::countNonZero(k(cv::Rect(80, 150, 15, 15))), 0);
  // Without a region (the prior found nobody) the mask is not touched.
  const Image untouched = KeepNearPerson(mask, PersonRegion{});
  EXPECT_EQ(untouched.data, mask.data);
  // What the other cameras' strict hull holds stays too (a part the prior lost in this frame),
  // and only that.
  Image hull(mask.width, mask.height, 1);
  AsCvMat(hull)(cv::Rect(80, 150, 15, 8)).setTo(255);
  const Image kept_with_hull = KeepNearPerson(mask, region, hull);
  const cv::Mat seen = AsCvMat(kept_with_hull);
  EXPECT_EQ(cv::countNonZero(seen(cv::Rect(80, 150, 15, 15))), 15 * 8);
  EXPECT_EQ(cv::countNonZero(seen), cv::countNonZero(k) + 15 * 8);
  // A region of another size is a usage error, not a wrong mask.
  EXPECT_THROW(KeepNearPerson(Image(50, 50, 1), region), UsageError);
  EXPECT_THROW(KeepNearPerson(mask, region, Image(50, 50, 1)), UsageError);
}

// A stand-in for segment.js: the same protocol, every crop answered with a person in its middle
// third (sure of it), and it exits after `answers` crops.
std::string StandInSegmenter(const testing::TempDir& dir, int answers) {
  testing::WriteFile(dir / "models/blazepose-full.bin", "");
  fs::create_directories(dir / "node_modules/@tensorflow/tfjs-backend-wasm");
  testing::WriteFile(dir / "segment.js", R"(
const kCrop = 256 * 256 * 3, kReply = 256 * 256 + (39 * 5 + 1) * 4;
let pending = Buffer.alloc(0), answered = 0;
process.stdout.write('CPSEG001');
process.stdin.on('data', (chunk) => {
  pending = Buffer.concat([pending, chunk]);
  while (pending.length >= kCrop) {
    pending = pending.subarray(kCrop);
    if (answered++ === )" + std::to_string(answers) + R"() process.exit(4);
    const reply = Buffer.alloc(kReply);
    for (let y = 64; y < 192; ++y) for (let x = 96; x < 160; ++x) reply[y * 256 + x] = 255;
    for (let i = 0; i < 39; ++i) reply.writeFloatLE(-10, 256 * 256 + 4 * (5 * i + 3));
    reply.writeFloatLE(1, kReply - 4);
    process.stdout.write(reply);
  }
});
process.stdin.on('end', () => process.exit(0));
)");
  return dir / "segment.js";
}

TEST(PersonPrior, CaptureRegionsAreSegmentedOnceAndADeadSegmenterIsReplaced) {
  testing::TempDir dir;
  PersonSegmenterOptions segmenter;
  // One frame takes 2 crops (the whole image, then the person's square, of which it is sure).
  segmenter.script = StandInSegmenter(dir, 2);
  CapturePersonPrior prior(segmenter, PersonPriorOptions{}, 2);
  const Image image(300, 300, 3);
  const PersonRegion first = prior.Region(0, 7, image, "cam00/000007.png", true);
  ASSERT_FALSE(first.region.empty());
  EXPECT_GT(first.height_px, 30);
  EXPECT_EQ(At(first.region, 150, 150), 255);
  EXPECT_EQ(At(first.region, 10, 10), 0);
  // Asked again, the kept region comes back without the segmenter, which has answered its 2 crops.
  // (Kept ones are given back once: the background's samples, then that frame's extraction.)
  const PersonRegion again = prior.Region(0, 7, image, "cam00/000007.png");
  EXPECT_EQ(again.region.data, first.region.data);
  EXPECT_EQ(again.core.data, first.core.data);
  EXPECT_DOUBLE_EQ(again.height_px, first.height_px);
  // A new frame meets the exhausted segmenter, which exits: the error names the image.
  try {
    prior.Region(1, 7, image, "cam01/000007.png");
    ADD_FAILURE() << "a dead segmenter answered";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("cam01/000007.png"), std::string::npos) << error.what();
  }
  // The dead one is not reused: two threads at once get fresh segmenters.
  PersonRegion a, b;
  std::thread one([&] { a = prior.Region(2, 0, image, "cam02"); });
  std::thread two([&] { b = prior.Region(3, 0, image, "cam03"); });
  one.join();
  two.join();
  EXPECT_EQ(a.region.data, first.region.data);
  EXPECT_EQ(b.region.data, first.region.data);
}

}  // namespace
}  // namespace confluent
