// Options of the basin paper's truth system (`sensors.overhead`): the overhead camera, the
// model's markers and the colour tracker (sim/sensors/overhead.hpp).
#pragma once

#include <array>

#include "core/yaml_io.hpp"

namespace driftlab::sim {

/// The two markers on the model's deck, on its centreline: red forward, green aft, so that
/// the direction from green to red is the model's heading (Eq. (11)).
struct MarkerOptions {
  double separation_m = 0.5;
  double diameter_m = 0.06;
  double centre_forward_m = 0.1;

  template <class A>
  void visit(A& a) {
    a("separation_m", separation_m,
      "Distance between the red (forward) and the green (aft) marker's centres [m]. Ours: the "
      "paper gives none; 0.5 m spans most of the 1.2 m model",
      yaml::positive() & yaml::up_to(100, "longer than any model"));
    a("diameter_m", diameter_m,
      "Diameter of each round marker [m]. Ours: 6 cm, about 24 pixels across from the "
      "default camera",
      yaml::positive() & yaml::up_to(10, "no marker is that large"));
    a("centre_forward_m", centre_forward_m,
      "Where the markers' midpoint (the paper's position, Eqs. (12)-(13)) lies ahead of the "
      "body origin [m]. Ours: 0.1 m, under the stereo camera (sensors.camera.mount), so that "
      "the reference and the camera's track coincide on a level model",
      yaml::in_range(-100, 100));
  }
};

/// An HSV box in OpenCV's 8-bit scales: hue 0-180 (degrees / 2), saturation and value 0-255.
/// A low hue above the high hue wraps through 0 (red).
struct HsvRange {
  std::array<double, 3> lo{0, 0, 0};
  std::array<double, 3> hi{180, 255, 255};

  template <class A>
  void visit(A& a) {
    a("lo", lo, "Lowest hue (0-180), saturation and value (0-255)", yaml::in_range(0, 255));
    a("hi", hi, "Highest hue (0-180), saturation and value (0-255)", yaml::in_range(0, 255));
    a.require(lo[0] <= 180 && hi[0] <= 180, "lo", "hues within 0-180 (OpenCV's 8-bit hue)");
  }
};

/// The paper's tracker (Section 3.2, after its reference [2], Rosebrock's ball tracker): the
/// steps and their sizes as that tracker has them.
struct MarkerTrackerOptions {
  int blur_kernel_px = 11;
  HsvRange red{{170, 120, 70}, {10, 255, 255}};
  HsvRange green{{40, 80, 50}, {85, 255, 255}};
  int erode_iterations = 2;
  int dilate_iterations = 2;

  template <class A>
  void visit(A& a) {
    a("blur_kernel_px", blur_kernel_px,
      "Side of the Gaussian blur's kernel [px] (odd; OpenCV's sigma for that size)",
      yaml::in_range(1, 99));
    a.require(blur_kernel_px % 2 == 1, "blur_kernel_px", "an odd number");
    a("red", red, "HSV thresholds of the red marker");
    a("green", green, "HSV thresholds of the green marker");
    a("erode_iterations", erode_iterations, "Erosions with a 3x3 square", yaml::in_range(0, 20));
    a("dilate_iterations", dilate_iterations, "Dilations with a 3x3 square", yaml::in_range(0, 20));
  }
};

/// The overhead camera (`sensors.overhead`): where the basin's ceiling mount holds it
/// (scenes::BasinLayout::camera_mount_W), looking straight down, image columns along north.
struct OverheadOptions {
  bool enabled = false;
  int width_px = 1280;
  int height_px = 720;
  double hfov_deg = 90.0;
  MarkerOptions markers;
  MarkerTrackerOptions tracker;

  template <class A>
  void visit(A& a) {
    a("enabled", enabled,
      "Render the basin's overhead camera at every stereo frame and track the model's markers "
      "into a second reference (the basin paper's truth, Section 3.2); wave_basin scenes only");
    a("width_px", width_px, "Image width [px] (the paper's 1280)", yaml::in_range(64, 8192));
    a("height_px", height_px, "Image height [px] (the paper's 720)", yaml::in_range(64, 8192));
    a("hfov_deg", hfov_deg,
      "Horizontal field of view [deg]. Ours: the paper gives none; 90 deg sees the whole "
      "tow from the default basin's ceiling",
      yaml::in_range(10, 150));
    a("markers", markers, "The red and green markers on the model");
    a("tracker", tracker, "The colour tracker");
  }
};

}  // namespace driftlab::sim
