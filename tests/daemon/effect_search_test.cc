// EffectSearch: kincal analyze's selection in a worker thread. On a window with a hidden
// delay it adds time_offset with its value and the held-out gain; on a clean window it
// adds nothing; one search at a time.
#include "daemon/effect_search.h"

#include <gtest/gtest.h>

#include "analysis/analysis_test_util.h"

namespace kincal::daemon {
namespace {

AnalyzeOptions SearchOptions() {
  AnalyzeOptions o;
  o.model = "unicycle";
  o.effects_mode = "auto";
  o.max_effects = 1;
  o.num_threads = 1;
  return o;
}

TEST(EffectSearch, FindsAHiddenDelayAndReportsTheGain) {
  EffectSearch search;
  const Recording rec = testing::UnicycleRecording(60.0, {"time_offset"}, {{"delay_s", 0.2}}, 3);
  ASSERT_TRUE(search.Start(rec, SearchOptions()));
  EXPECT_FALSE(search.Start(rec, SearchOptions()));  // one at a time
  const EffectSearchResult r = search.Wait();
  ASSERT_TRUE(r.ok) << r.error;
  ASSERT_EQ(r.added, std::vector<std::string>{"time_offset"}) << r.evidence;
  bool found = false;
  for (const ParamEstimate& p : r.params) {
    if (p.name != "delay_s") continue;
    found = true;
    EXPECT_NEAR(p.value, 0.2, std::max(0.01, 3 * p.sigma));
  }
  EXPECT_TRUE(found);
  EXPECT_LT(r.heldout_after_m, 0.5 * r.heldout_before_m);
  EXPECT_FALSE(search.running());
  EXPECT_FALSE(search.Poll().has_value());  // the result was handed over once
}

TEST(EffectSearch, CleanWindowAddsNothing) {
  EffectSearch search;
  ASSERT_TRUE(search.Start(testing::UnicycleRecording(60.0, {}, {}, 4), SearchOptions()));
  const EffectSearchResult r = search.Wait();
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_TRUE(r.added.empty()) << r.evidence;
}

TEST(EffectSearch, TooLittleDataIsAnErrorNotACrash) {
  EffectSearch search;
  ASSERT_TRUE(search.Start(testing::UnicycleRecording(1.0, {}, {}, 5), SearchOptions()));
  const EffectSearchResult r = search.Wait();
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.error.empty());
}

}  // namespace
}  // namespace kincal::daemon
