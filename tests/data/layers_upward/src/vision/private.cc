// A fixture for cmake/CheckLayers.cmake: vision may use estimation's public headers, not
// its private ones.
#include "estimation/filter_util.h"
#include "kincal/estimation/batch.h"
