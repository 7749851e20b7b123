// SPDX-License-Identifier: BSD-3-Clause
// Unknown keys in the files the tools read (calibration and scene files) are errors that name the
// nearest known key: a misspelled key must not silently become a default.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

namespace cylfe {

// Levenshtein distance (insertions, deletions, substitutions).
inline size_t edit_distance(const std::string &a, const std::string &b)
{
    std::vector<size_t> d(b.size() + 1);
    for (size_t j = 0; j <= b.size(); j++) d[j] = j;
    for (size_t i = 1; i <= a.size(); i++) {
        size_t prev = d[0];
        d[0] = i;
        for (size_t j = 1; j <= b.size(); j++) {
            size_t cur = d[j];
            d[j] = std::min({d[j] + 1, d[j - 1] + 1, prev + (a[i - 1] == b[j - 1] ? 0 : 1)});
            prev = cur;
        }
    }
    return d[b.size()];
}

// " (did you mean 'K'?)" for the known key K nearest to `key` within 3 edits, else "".
inline std::string did_you_mean(const std::string &key, const std::vector<std::string> &known)
{
    std::string best;
    size_t bd = 4;
    for (const std::string &k : known) {
        size_t d = edit_distance(key, k);
        if (d < bd) { bd = d; best = k; }
    }
    return best.empty() ? std::string() : " (did you mean '" + best + "'?)";
}

} // namespace cylfe
