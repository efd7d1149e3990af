/* gearsim/gearsim.h - umbrella header of the gearsim C core. */
#ifndef GEARSIM_GEARSIM_H
#define GEARSIM_GEARSIM_H

#include "gearsim/types.h"
#include "gearsim/simple_gear.h"
#include "gearsim/rack_pinion.h"
#include "gearsim/rig.h"

#endif /* GEARSIM_GEARSIM_H */
