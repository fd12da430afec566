#include "studies.h"
int study_speed(const study_env *env) { (void)env; return 0; }
