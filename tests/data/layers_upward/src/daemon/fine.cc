// A fixture for cmake/CheckLayers.cmake: the daemon may use every layer below it.
#include "daemon/own.h"
#include "kincal/io/recording.h"
#include "kincal/plan/planner.h"
