/* assembly.h -- the balanced binary assembly tree (MATH.md §10), built by
 * tree contraction (rake and compress), and its pooled node memory. */
#ifndef AQS_ASSEMBLY_H
#define AQS_ASSEMBLY_H

#include "linkage.h"

/* Build L->t from L->m. Returns AQS_OK or AQS_ENOMEM (L->t then empty). */
aqs_status assembly_build(aqs_linkage *L);
void assembly_free(aqs_linkage *L);

#endif
