// The mip levels of an alpha-tested texture (leaf-cluster cards), computed on the CPU so that
// every level covers as much as level 0. A plain box filter does not: averaging a leaf's edge
// with the gaps around it pulls alpha under the test's threshold, and cards thin out and vanish
// with distance (a crown seen from 100 m would be mostly holes). Castaño (2010), "Computing
// alpha mipmaps": scale each level's alpha so that the share of texels that pass the test
// equals level 0's.
#pragma once

#include <cstdint>
#include <vector>

#include "sim/render/scene_geometry.hpp"

namespace driftlab::sim {

/// One level: grey and alpha interleaved (GL_RG), row-major.
struct AlphaMipLevel {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> grey_alpha;
};

/// The share of texels whose alpha is at least kAlphaOpaqueFrom.
double alpha_coverage(const std::vector<std::uint8_t>& alpha);

/// Levels 0.. of a texture with alpha (sizes as OpenGL makes them, down to 1x1). Level k's texel
/// covers a block of level 0 (never of level k - 1, so rounding does not compound): its alpha is
/// the block's mean scaled by one factor per level, chosen so that exactly round(c0 N_k) texels
/// reach kAlphaOpaqueFrom (c0: level 0's coverage, N_k: the level's texels; ties at the
/// threshold broken by index); its grey is the block's alpha-weighted mean, so the colour of
/// transparent texels does not bleed into the leaves. Throws InternalError if the texture has
/// no alpha or inconsistent sizes. Pure and deterministic.
std::vector<AlphaMipLevel> coverage_preserving_mips(const Texture& texture);

}  // namespace driftlab::sim
