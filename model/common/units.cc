#include "model/common/units.h"
