// Acceptance test 2 (exact sparsity, Eustice, Singh & Leonard ICRA 2005 Fig. 2): after a long
// simulated survey the information matrix holds exactly the delayed-state chain, the
// robot-newest pair and one block pair per distinct camera link; nothing else.
#include "nav/core/filter/esdf.h"
#include "nav/core/sim/survey.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <utility>

namespace nav::core {
namespace {

using Pair = std::pair<int, int>;
Pair ordered(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

TEST(EsdfSparsity, OnlyChainAndCameraLinksAfterLongSurvey) {
  sim::SurveyOptions opt;
  opt.num_images = 300;
  opt.seed = 5;
  const sim::Survey sv = sim::simulate_survey(opt);
  Esdf esdf(12);
  ASSERT_TRUE(esdf.initialize(sv.x0_mean, sv.P0).ok());
  std::vector<int> image_blocks;
  std::set<Pair> link_pairs;
  for (const sim::SurveyStep& st : sv.steps) {
    const Status s = sim::apply_step(sv, st, esdf, image_blocks);
    ASSERT_TRUE(s.ok()) << s.to_string();
    for (const sim::CameraLink& l : st.links) {
      link_pairs.insert(ordered(image_blocks[static_cast<size_t>(l.image_a)],
                                image_blocks[static_cast<size_t>(l.image_b)]));
    }
    if (st.image >= 0 && st.image % 4 == 0) {  // linearisation point refreshed every 4 images
      ASSERT_TRUE(esdf.recover_mean_direct().ok());
    }
  }
  ASSERT_EQ(image_blocks.size(), 300u);
  ASSERT_EQ(esdf.num_blocks(), 301);
  ASSERT_GT(sv.num_cross_track_links, 50u) << "survey should close many loops";

  // Expected pattern: chain between consecutive images, robot-newest image, camera links.
  std::set<Pair> chain;
  for (size_t i = 0; i + 1 < image_blocks.size(); ++i) {
    chain.insert(ordered(image_blocks[i], image_blocks[i + 1]));
  }
  chain.insert(ordered(Esdf::kRobotBlock, image_blocks.back()));
  std::set<Pair> expected = chain;
  expected.insert(link_pairs.begin(), link_pairs.end());
  size_t links_off_chain = 0;
  for (const Pair& p : link_pairs) links_off_chain += chain.count(p) == 0 ? 1 : 0;

  const InformationMatrix& L = esdf.information();
  EXPECT_EQ(L.num_off_diagonal_pairs(), chain.size() + links_off_chain);
  EXPECT_EQ(L.num_off_diagonal_pairs(), expected.size());
  std::set<Pair> stored;
  for (int i = 0; i < L.num_blocks(); ++i) {
    for (int j : L.neighbours(i)) {
      stored.insert(ordered(i, j));
      EXPECT_TRUE(expected.count(ordered(i, j)) == 1)
          << "unexpected fill-in between blocks " << i << " and " << j;
      EXPECT_GT(L.find_block(i, j)->cwiseAbs().maxCoeff(), 0.0) << i << "," << j;
    }
  }
  EXPECT_EQ(stored, expected);
  // The compressed matrix holds the same pattern: 144 entries per stored block.
  const auto S = L.to_sparse();
  EXPECT_EQ(static_cast<size_t>(S.nonZeros()), 144u * (301u + 2u * expected.size()));
  const double fill = static_cast<double>(S.nonZeros()) / (static_cast<double>(S.rows()) * S.cols());
  std::printf("300 images: %zu camera links (%zu cross-track), %zu stored block pairs, "
              "non-zero fraction %.4f %%\n",
              sv.num_links, sv.num_cross_track_links, expected.size(), 100.0 * fill);
}

}  // namespace
}  // namespace nav::core
