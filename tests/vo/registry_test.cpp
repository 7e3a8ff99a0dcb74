// The VO registry: names a plug-in may take, and a registered VO made by name.
#include "vo/registry.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "tests/support/test_support.hpp"

#include "core/error.hpp"

namespace driftlab::vo {
namespace {

class FixedVo final : public StereoOdometry {
 public:
  explicit FixedVo(double x) : x_(x) {}
  VoResult process(const StereoFrame&) override {
    VoResult r;
    r.valid = true;
    r.T_prev_curr = SE3(Quat::Identity(), Vec3(x_, 0, 0));
    return r;
  }
  void reset() override {}
  std::string name() const override { return "fixed"; }

 private:
  double x_;
};

TEST(VoRegistry, RegistersByNameAndRefusesTakenOrUnsafeNames) {
  const VoFactory factory = [](const StereoRig& rig, Rng) {
    return std::make_unique<FixedVo>(rig.baseline_m);
  };
  EXPECT_EQ(make_registered_vo("fixed_test", StereoRig{}, Rng(1)), nullptr);
  register_vo("fixed_test", factory);
  EXPECT_NE(driftlab::test::user_error_of([&] {
              register_vo("fixed_test", factory);
            }).find("already registered"),
            std::string::npos);
  EXPECT_NE(driftlab::test::user_error_of([&] {
              register_vo("sparse", factory);
            }).find("a built-in VO's name"),
            std::string::npos);
  EXPECT_NE(
      driftlab::test::user_error_of([&] { register_vo("a b", factory); }).find("letters, digits"),
      std::string::npos);
  EXPECT_NE(
      driftlab::test::user_error_of([&] { register_vo("", factory); }).find("letters, digits"),
      std::string::npos);
  const auto names = available_vo_names();
  EXPECT_EQ(names.front(), "sparse");
  EXPECT_EQ(names.back(), "fixed_test");
  StereoRig rig;
  rig.baseline_m = 0.3;  // the factory gets the rig it is made for
  const auto vo = make_registered_vo("fixed_test", rig, Rng(1));
  ASSERT_NE(vo, nullptr);
  EXPECT_EQ(vo->process({}).T_prev_curr.translation().x(), 0.3);
}

struct FixedOptions {
  double step_m = 0.5;
  template <class A>
  void visit(A& a) {
    a("step_m", step_m, "Step per frame [m]", yaml::positive());
  }
};

struct PluginsOnly {  // pipeline.plugins alone
  yaml::NamedOptions plugins = plugin_options();
  template <class A>
  void visit(A& a) {
    a("plugins", plugins, "");
  }
};

TEST(VoRegistry, AVoWithOptionsGetsThemFromPipelinePluginsOrItsDefaults) {
  register_vo<FixedOptions>("fixed_opts_test", [](const StereoRig&, Rng, const FixedOptions& o) {
    return std::make_unique<FixedVo>(o.step_m);
  });
  yaml::NamedOptions plugins = plugin_options();
  EXPECT_NE(
      std::find(plugins.known_names().begin(), plugins.known_names().end(), "fixed_opts_test"),
      plugins.known_names().end());
  // Not given: the options struct's defaults.
  EXPECT_EQ(make_registered_vo("fixed_opts_test", {}, Rng(1), plugins)
                ->process({})
                .T_prev_curr.translation()
                .x(),
            0.5);
  PluginsOnly h;
  yaml::read_into(yaml::override_document("plugins.fixed_opts_test.step_m=2"), {"--set", false},
                  &h);
  EXPECT_EQ(make_registered_vo("fixed_opts_test", {}, Rng(1), h.plugins)
                ->process({})
                .T_prev_curr.translation()
                .x(),
            2.0);
  EXPECT_NE(driftlab::test::user_error_of([&] {
              register_vo<FixedOptions>("fixed_opts_test",
                                        [](const StereoRig&, Rng, const FixedOptions& o) {
                                          return std::make_unique<FixedVo>(o.step_m);
                                        });
            }).find("already registered"),
            std::string::npos);
}

}  // namespace
}  // namespace driftlab::vo
