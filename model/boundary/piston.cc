#include "model/boundary/piston.h"
