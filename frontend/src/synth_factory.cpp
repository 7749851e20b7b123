// SPDX-License-Identifier: BSD-3-Clause
// open_source("synthetic[:SEED]"): the synthetic scene of cylfe::synth (frontend/src/synth/).
#include "cylfe/sources.hpp"
#include "cylfe/synth.hpp"

namespace cylfe {

std::unique_ptr<Source> make_synthetic_source(const SourceOptions &opt)
{
    synth::Scene scene = synth::scene_by_name(opt.scene.empty() ? "default" : opt.scene);
    return std::unique_ptr<Source>(new synth::SyntheticSource(scene, opt.frames ? (uint32_t)opt.frames : 1000u, opt.seed));
}

} // namespace cylfe
