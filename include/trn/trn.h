/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file trn.h
 * @brief Umbrella header of the trn core: terrain-matching localization and
 * landmark selection after C. F. Olson, "Landmark Selection for Terrain
 * Matching", ICRA 2000. Pure C99, no allocation, no OS calls.
 */
#ifndef TRN_TRN_H
#define TRN_TRN_H

#include "trn/trn_config.h"
#include "trn/status.h"
#include "trn/grid.h"
#include "trn/terrain.h"
#include "trn/chamfer.h"
#include "trn/likelihood.h"
#include "trn/peakfit.h"
#include "trn/refine.h"
#include "trn/localize.h"
#include "trn/kernels.h"
#include "trn/spread.h"
#include "trn/select.h"
#include "trn/field.h"
#include "trn/mast.h"
#include "trn/heading.h"
#include "trn/height_heading.h"
#include "trn/abi.h"

#endif /* TRN_TRN_H */
