#pragma once
// Unconstrained correspondence search: every descriptor of image i against every descriptor of
// image j, kept when (a) Lowe's ratio test passes (nearest distance < ratio x second nearest;
// Lowe, IJCV 60(2), 2004, section 7.1) and (b) the match is mutual (i's nearest in j has i as
// its nearest in i). Used for pairs without a pose prior and as the baseline against which the
// pose-constrained search (pccs.h) is measured; descriptor_comparisons counts the distances
// evaluated (|i| x |j|).

#include "nav/vision/vision_types.h"

namespace nav::vision {

struct MatchingOptions {
  double ratio = 0.8;         ///< Lowe's ratio of nearest to second-nearest distance.
  bool mutual = true;         ///< Keep only mutual nearest neighbours.
  float max_distance = 1e9f;  ///< Absolute descriptor-distance ceiling.
};

PutativeMatches match_unconstrained(const ImageFeatures& features_i,
                                    const ImageFeatures& features_j,
                                    const MatchingOptions& options = {});

}  // namespace nav::vision
