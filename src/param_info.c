/* param_info.c - the run-time parameter tables (gs_*_param_info), expanded
 * from the lists of gearsim/parameters.h for generic readers: the Python
 * package, the HIL runner's parameter file, the FMUs. Nothing in the step
 * reads them, so a firmware image that does not refer to them leaves them
 * out. tests/c/test_param_tables.c checks that each table covers every byte
 * of its struct. */
#include <stddef.h>

#include "gearsim/gearsim.h"

#define GS_STR_(x)       #x
#define GS_XSTR_(x)      GS_STR_(x)
#define GS_FIRST_(a, b)  a
#define GS_SECOND_(a, b) b

/* ---- option lists: gs_options_<name>_ */
#define GS_OPTION_ITEM_(enumerator, name, doc) {#enumerator, name, doc, (int)(enumerator)},
#define GS_OPTION_LIST_(set)                                                                       \
    static const gs_param_option gs_option_items_##set##_[] = {GS_OPTIONS_##set(GS_OPTION_ITEM_)}; \
    static const gs_param_options gs_options_##set##_ = {#set, gs_option_items_##set##_,           \
                                                         sizeof(gs_option_items_##set##_) / sizeof(gs_param_option)};
GS_OPTION_LISTS(GS_OPTION_LIST_)
static const gs_param_options gs_options_NONE_ = {"", NULL, 0};

/* ---- per-kind fields of an entry */

/* length, columns, count, count2, members, member_count */
#define GS_PARAM_SCALAR_                     1u, 1u, "", "", NULL, 0u
#define GS_PARAM_SHAPE_REAL(member, count)   GS_PARAM_SCALAR_
#define GS_PARAM_SHAPE_INT(member, count)    GS_PARAM_SCALAR_
#define GS_PARAM_SHAPE_BOOL(member, count)   GS_PARAM_SCALAR_
#define GS_PARAM_SHAPE_OPTION(member, count) GS_PARAM_SCALAR_
#define GS_PARAM_SHAPE_COUNT(member, count)  GS_PARAM_SCALAR_
#define GS_PARAM_SHAPE_ARRAY(member, count)  (size_t)(count), 1u, "", "", NULL, 0u
#define GS_PARAM_SHAPE_TABLE(member, count)  (size_t) GS_TABLE_MAX, 1u, #count, "", NULL, 0u
#define GS_PARAM_SHAPE_MATRIX(member, count) \
    (size_t) GS_TABLE_MAX, (size_t)GS_TABLE_MAX, GS_XSTR_(GS_FIRST_ count), GS_XSTR_(GS_SECOND_ count), NULL, 0u
#define GS_PARAM_SHAPE_GROUP(member, count) \
    1u, 1u, "", "", gs_##member##_param_info, sizeof(gs_##member##_param_info) / sizeof(gs_param_info)

#define GS_PARAM_INFO_(T, kind, member, count, key, rack_key, gear_unit, rack_unit, options, flags, doc) \
    {key,                                                                                                \
     rack_key,                                                                                           \
     #member,                                                                                            \
     gear_unit,                                                                                          \
     rack_unit,                                                                                          \
     doc,                                                                                                \
     GS_PARAM_##kind,                                                                                    \
     GS_PARAM_##flags,                                                                                   \
     offsetof(T, member),                                                                                \
     sizeof(((T *)NULL)->member),                                                                        \
     GS_PARAM_SHAPE_##kind(member, count),                                                               \
     &gs_options_##options##_},

/* A block list has one key and one unit for both rigs. */
#define GS_BACKLASH_INFO_(kind, type, member, count, key, unit, options, flags, doc) \
    GS_PARAM_INFO_(gs_backlash_params, kind, member, count, key, key, unit, unit, options, flags, doc)
#define GS_SIMPLE_GEAR_INFO_(kind, type, member, count, key, unit, options, flags, doc) \
    GS_PARAM_INFO_(gs_simple_gear_params, kind, member, count, key, key, unit, unit, options, flags, doc)
#define GS_RACK_PINION_INFO_(kind, type, member, count, key, unit, options, flags, doc) \
    GS_PARAM_INFO_(gs_rack_pinion_params, kind, member, count, key, key, unit, unit, options, flags, doc)
#define GS_RIG_INFO_(kind, type, member, count, key, rack_key, gear_unit, rack_unit, options, flags, doc) \
    GS_PARAM_INFO_(gs_rig_params, kind, member, count, key, rack_key, gear_unit, rack_unit, options, flags, doc)

const gs_param_info gs_backlash_param_info[GS_BACKLASH_PARAM_FIELDS] = {GS_BACKLASH_PARAM_LIST(GS_BACKLASH_INFO_)};
const gs_param_info gs_simple_gear_param_info[GS_SIMPLE_GEAR_PARAM_FIELDS] = {
    GS_SIMPLE_GEAR_PARAM_LIST(GS_SIMPLE_GEAR_INFO_)};
const gs_param_info gs_rack_pinion_param_info[GS_RACK_PINION_PARAM_FIELDS] = {
    GS_RACK_PINION_PARAM_LIST(GS_RACK_PINION_INFO_)};
const gs_param_info gs_rig_param_info[GS_RIG_PARAM_FIELDS] = {GS_RIG_PARAM_LIST(GS_RIG_INFO_)};
