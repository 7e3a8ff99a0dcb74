// Photographed materials (the river-bank issue): real photographs of grass, soil, bark,
// stones, bricks and concrete from Debian 12's ufoai-textures package, used as the river
// reach's textures in place of the procedural ones. scripts/fetch-materials downloads the
// package from the Debian archive (it is not installed), extracts the files that the manifest
// scenes/assets/photographs.tsv names and checks their SHA-256; the scene builder checks them
// again when it reads them, so the same scenario and seed give the same frames on every
// machine. The photographs are never committed; the README credits them.
#pragma once

#include <string>
#include <vector>

#include "scenes/textures.hpp"
#include "sim/render/scene_geometry.hpp"

namespace driftlab::scenes {

/// One row of the manifest: the material, the file's SHA-256, where the package keeps it,
/// how to turn it, its licence and its authors.
struct PhotographEntry {
  std::string kind;       // a texture_kind_name(), e.g. "bark"
  std::string sha256;     // of the file as the package ships it (lower-case hex)
  std::string source;     // path inside the package's 0textures.pk3 (a zip)
  int quarter_turns = 0;  // clockwise, 0-3: bark stored sideways gets its furrows upright
  std::string licence;
  std::string credit;
  int line = 0;  // in the manifest, for messages

  /// The file's name in the materials folder: the kind and the source's extension.
  std::string file_name() const;
};

/// The manifest (shipped_asset("photographs.tsv")): tab-separated rows kind, sha256, source,
/// quarter_turns, licence, credit; '#' starts a comment line. Throws UserError naming the file,
/// line and field of a malformed row.
std::vector<PhotographEntry> photograph_manifest();

/// The folder the photographs are read from: $DRIFTLAB_MATERIALS, else
/// $XDG_DATA_HOME/driftlab/materials, else $HOME/.local/share/driftlab/materials (where
/// scripts/fetch-materials puts them by default).
std::string materials_dir();

/// SHA-256 of `bytes` (lower-case hex).
std::string sha256_hex(const std::string& bytes);

/// The photograph of `kind` as a grayscale texture named like the procedural one: read from
/// materials_dir(), checked against the manifest's SHA-256, decoded to gray (ITU-R BT.601
/// luma), turned by the row's quarter_turns, made square by repeating a tiling photograph whose one
/// side is a whole multiple of the other, halved (each pixel the rounded mean of 2x2) until its
/// edge is at most `max_edge_px`, and scaled so that its mean grey is `mean_gray` (the procedural
/// texture's, so the materials' albedos keep their meaning). Throws UserError when the manifest has
/// no photograph of `kind`, or the file is missing, differs from the one the manifest names, or
/// cannot be decoded, with what to do about it.
sim::Texture load_photograph(TextureKind kind, double mean_gray, int max_edge_px = 1024);

/// Mean grey of a texture's pixels.
double mean_gray(const sim::Texture& t);

}  // namespace driftlab::scenes
