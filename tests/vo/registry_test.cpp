// The VO registry: names a plug-in may take, and a registered VO made by name.
#include "vo/registry.hpp"

#include <gtest/gtest.h>

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

const auto error_of = driftlab::test::user_error_of;

TEST(VoRegistry, RegistersByNameAndRefusesTakenOrUnsafeNames) {
  const VoFactory factory = [](const StereoRig& rig, Rng) {
    return std::make_unique<FixedVo>(rig.baseline_m);
  };
  EXPECT_EQ(make_registered_vo("fixed_test", StereoRig{}, Rng(1)), nullptr);
  register_vo("fixed_test", factory);
  EXPECT_NE(error_of([&] { register_vo("fixed_test", factory); }).find("already registered"),
            std::string::npos);
  EXPECT_NE(error_of([&] { register_vo("sparse", factory); }).find("a built-in VO's name"),
            std::string::npos);
  EXPECT_NE(error_of([&] { register_vo("a b", factory); }).find("letters, digits"),
            std::string::npos);
  EXPECT_NE(error_of([&] { register_vo("", factory); }).find("letters, digits"), std::string::npos);
  const auto names = available_vo_names();
  EXPECT_EQ(names.front(), "sparse");
  EXPECT_EQ(names.back(), "fixed_test");
  StereoRig rig;
  rig.baseline_m = 0.3;  // the factory gets the rig it is made for
  const auto vo = make_registered_vo("fixed_test", rig, Rng(1));
  ASSERT_NE(vo, nullptr);
  EXPECT_EQ(vo->process({}).T_prev_curr.translation().x(), 0.3);
}

}  // namespace
}  // namespace driftlab::vo
