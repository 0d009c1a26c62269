// A fixture for cmake/CheckLayers.cmake: io may not use the daemon (a layer above it).
#include "kincal/daemon/daemon.h"
