#pragma once

#include "drivers/sim/builtin_scenes.h"

namespace cblox {

/// (d) A walled courtyard (30 x 30 m, 4 m walls) scattered with about 70 boxes, turned
/// boxes, stacks, cylinders (standing and lying), cones, spheres and pipe arches of varied
/// sizes and colours, with doors and plaques on the walls. It is the TRAINING scene of the
/// place-recognition vocabulary (cblox-vocabulary train --source sim:yard): room, hall and
/// town are evaluation scenes and must not be trained on. Objects are placed by seeded
/// rejection sampling that keeps them at least 1.5 m (horizontally) from every path of the
/// scene, so all trajectory kinds fly clear. Deterministic. Thread-safe (pure).
BuiltinScene makeTrainingYard();

}  // namespace cblox
