/* Type name ("cell::StationStatus") -> idlc topic descriptor, or NULL. Generated body. */
#ifndef CELL_CYCLONE_REGISTRY_H
#define CELL_CYCLONE_REGISTRY_H
#include <dds/dds.h>
#ifdef __cplusplus
extern "C" {
#endif
const dds_topic_descriptor_t* cell_cyclone_descriptor(const char* type_name);
#ifdef __cplusplus
}
#endif
#endif
