#include "studies.h"
int study_artefact(const study_env *env) { (void)env; return 0; }
