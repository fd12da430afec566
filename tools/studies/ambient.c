#include "studies.h"
int study_ambient(const study_env *env) { (void)env; return 0; }
