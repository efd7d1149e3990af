/*
 * test_param_tables.c - the run-time parameter tables of gearsim/parameters.h
 * (gs_rig_param_info, gs_simple_gear_param_info, gs_rack_pinion_param_info,
 * gs_backlash_param_info) against the structs they describe:
 *  - coverage: each table covers every byte of its struct, in member order,
 *    with no overlap and no gap but the padding the members' alignment
 *    requires (nested groups checked the same way); the checker itself is
 *    shown to fail on doctored tables (a dropped entry, a shifted offset, a
 *    wrong size), so that it cannot pass vacuously;
 *  - consistency: keys unique in each rig, table counts naming count
 *    entries, option lists with distinct values 0..n-1 and names;
 *  - spot checks of facts the documentation states (the driven side's two
 *    names and units, the Rack & Pinion's three meshing-loss models, the
 *    ripple's two harmonics, the 10 x 10 efficiency matrix).
 * Built and run in both precisions, like every C test.
 */
#include "test_common.h"

#define MAX_ENTRIES 64

static size_t round_up(size_t n, size_t align)
{
    return (n + align - 1u) / align * align;
}

/* Alignment of the scalar types the params structs are made of, measured
 * independently of the tables. */
typedef struct {
    char c;
    gs_real x;
} real_probe;
typedef struct {
    char c;
    int x;
} int_probe;
typedef struct {
    char c;
    gs_friction_model x;
} enum_probe;

static size_t scalar_alignment(size_t element_size)
{
    if (element_size == sizeof(gs_real)) {
        return offsetof(real_probe, x);
    }
    if (element_size == sizeof(int)) {
        return offsetof(int_probe, x);
    }
    if (element_size == sizeof(gs_friction_model)) {
        return offsetof(enum_probe, x);
    }
    return 0; /* unknown element type: the checker reports it */
}

/* The element size a kind allows: gs_real for numbers, int for integers and
 * counts, int or an enum for flags and options. */
static int element_fits_kind(gs_param_kind kind, size_t element_size)
{
    switch (kind) {
    case GS_PARAM_REAL:
    case GS_PARAM_ARRAY:
    case GS_PARAM_TABLE:
    case GS_PARAM_MATRIX:
        return element_size == sizeof(gs_real);
    case GS_PARAM_INT:
    case GS_PARAM_COUNT:
        return element_size == sizeof(int);
    case GS_PARAM_BOOL:
    case GS_PARAM_OPTION:
        return element_size == sizeof(int) || element_size == sizeof(gs_friction_model);
    case GS_PARAM_GROUP:
        return 0;
    }
    return 0;
}

/* Checks that table[0..n) covers a struct of struct_size bytes. Returns NULL
 * or what is wrong; *alignment receives the struct's alignment. */
static const char *check_coverage(const gs_param_info *table, size_t n, size_t struct_size, size_t *alignment)
{
    static char message[256];
    unsigned char owner[4096];
    size_t end = 0;
    size_t struct_align = 1;
    if (struct_size > sizeof owner) {
        return "struct larger than the test's byte map";
    }
    memset(owner, 0, sizeof owner);
    for (size_t i = 0; i < n; ++i) {
        const gs_param_info *e = &table[i];
        size_t align = 0;
        if (e->kind == GS_PARAM_GROUP) {
            const char *inner = check_coverage(e->members, e->member_count, e->size, &align);
            if (inner != NULL) {
                return inner;
            }
        } else {
            const size_t values = e->length * e->columns;
            if (values == 0 || e->size % values != 0) {
                snprintf(message, sizeof message, "%s: size %zu is not %zu values", e->member, e->size, values);
                return message;
            }
            if (!element_fits_kind(e->kind, e->size / values)) {
                snprintf(message, sizeof message, "%s: %zu-byte elements for its kind", e->member, e->size / values);
                return message;
            }
            align = scalar_alignment(e->size / values);
        }
        if (align == 0) {
            snprintf(message, sizeof message, "%s: element of unknown alignment", e->member);
            return message;
        }
        if (e->offset != round_up(end, align)) {
            snprintf(message, sizeof message, "%s: offset %zu, expected %zu (previous member ends at %zu)", e->member,
                     e->offset, round_up(end, align), end);
            return message;
        }
        if (e->offset + e->size > struct_size) {
            snprintf(message, sizeof message, "%s: ends past the struct", e->member);
            return message;
        }
        for (size_t b = e->offset; b < e->offset + e->size; ++b) {
            if (owner[b]) {
                snprintf(message, sizeof message, "%s: byte %zu described twice", e->member, b);
                return message;
            }
            owner[b] = 1;
        }
        end = e->offset + e->size;
        struct_align = align > struct_align ? align : struct_align;
    }
    if (round_up(end, struct_align) != struct_size) {
        snprintf(message, sizeof message, "the entries end at %zu, the struct is %zu bytes", end, struct_size);
        return message;
    }
    /* the bytes not described are exactly the padding */
    size_t described = 0;
    for (size_t b = 0; b < struct_size; ++b) {
        described += owner[b];
    }
    size_t padding = 0;
    size_t at = 0;
    for (size_t i = 0; i < n; ++i) {
        padding += table[i].offset - at;
        at = table[i].offset + table[i].size;
    }
    padding += struct_size - at;
    if (described + padding != struct_size) {
        return "described bytes and padding do not add up to the struct";
    }
    *alignment = struct_align;
    return NULL;
}

static void assert_covers(const gs_param_info *table, size_t n, size_t struct_size, const char *what)
{
    size_t align = 0;
    const char *problem = check_coverage(table, n, struct_size, &align);
    if (problem != NULL) {
        print_error("%s: %s\n", what, problem);
    }
    assert_null(problem);
}

static void test_tables_cover_their_structs(void **state)
{
    (void)state;
    assert_covers(gs_backlash_param_info, GS_BACKLASH_PARAM_FIELDS, sizeof(gs_backlash_params), "backlash");
    assert_covers(gs_simple_gear_param_info, GS_SIMPLE_GEAR_PARAM_FIELDS, sizeof(gs_simple_gear_params), "gear");
    assert_covers(gs_rack_pinion_param_info, GS_RACK_PINION_PARAM_FIELDS, sizeof(gs_rack_pinion_params), "rack");
    assert_covers(gs_rig_param_info, GS_RIG_PARAM_FIELDS, sizeof(gs_rig_params), "rig");
}

/* The checker fails on tables that do not describe their struct. */
static void test_checker_finds_doctored_tables(void **state)
{
    (void)state;
    gs_param_info copy[MAX_ENTRIES];
    size_t align = 0;
    const size_t n = GS_RIG_PARAM_FIELDS;
    assert_true(n <= MAX_ENTRIES);
    for (size_t drop = 0; drop < n; ++drop) { /* any entry left out */
        size_t k = 0;
        for (size_t i = 0; i < n; ++i) {
            if (i != drop) {
                copy[k++] = gs_rig_param_info[i];
            }
        }
        if (check_coverage(copy, k, sizeof(gs_rig_params), &align) == NULL) {
            print_error("dropping %s passes\n", gs_rig_param_info[drop].member);
        }
        assert_non_null(check_coverage(copy, k, sizeof(gs_rig_params), &align));
    }
    for (size_t i = 0; i < n; ++i) { /* any offset moved, any size wrong */
        memcpy(copy, gs_rig_param_info, sizeof(gs_rig_param_info));
        copy[i].offset += sizeof(gs_real);
        assert_non_null(check_coverage(copy, n, sizeof(gs_rig_params), &align));
        memcpy(copy, gs_rig_param_info, sizeof(gs_rig_param_info));
        copy[i].size += copy[i].size / (copy[i].length * copy[i].columns);
        assert_non_null(check_coverage(copy, n, sizeof(gs_rig_params), &align));
    }
    /* a nested group's table with an entry missing */
    gs_param_info backlash[MAX_ENTRIES];
    memcpy(backlash, gs_backlash_param_info, sizeof(gs_backlash_param_info));
    memcpy(copy, gs_rack_pinion_param_info, sizeof(gs_rack_pinion_param_info));
    for (size_t i = 0; i < GS_RACK_PINION_PARAM_FIELDS; ++i) {
        if (copy[i].kind == GS_PARAM_GROUP) {
            copy[i].members = backlash + 1;
            copy[i].member_count = GS_BACKLASH_PARAM_FIELDS - 1u;
        }
    }
    assert_non_null(check_coverage(copy, GS_RACK_PINION_PARAM_FIELDS, sizeof(gs_rack_pinion_params), &align));
    /* and the unchanged copy passes */
    memcpy(copy, gs_rack_pinion_param_info, sizeof(gs_rack_pinion_param_info));
    assert_null(check_coverage(copy, GS_RACK_PINION_PARAM_FIELDS, sizeof(gs_rack_pinion_params), &align));
}

static const gs_param_info *find(const gs_param_info *table, size_t n, const char *member)
{
    for (size_t i = 0; i < n; ++i) {
        if (strcmp(table[i].member, member) == 0) {
            return &table[i];
        }
    }
    return NULL;
}

static void check_options(const gs_param_info *e)
{
    const gs_param_options *o = e->options;
    assert_non_null(o);
    if (e->kind == GS_PARAM_OPTION) {
        assert_true(o->count >= 2);
    }
    if (e->kind == GS_PARAM_BOOL && o->count > 0) {
        assert_int_equal(o->count, 2); /* a two-valued enum: false, true */
    }
    if (o->count == 0) {
        assert_string_equal(o->name, "");
        assert_null(o->items);
        return;
    }
    assert_true(strlen(o->name) > 0);
    for (size_t k = 0; k < o->count; ++k) {
        assert_true(strncmp(o->items[k].enumerator, "GS_", 3) == 0);
        assert_true(strlen(o->items[k].name) > 0 && strlen(o->items[k].doc) > 0);
        for (size_t j = 0; j < k; ++j) {
            assert_true(o->items[j].value != o->items[k].value);
            assert_true(strcmp(o->items[j].name, o->items[k].name) != 0);
        }
    }
}

/* Table-local facts: counts name count entries, option lists, units only on
 * numbers. */
static void check_table(const gs_param_info *table, size_t n)
{
    for (size_t i = 0; i < n; ++i) {
        const gs_param_info *e = &table[i];
        assert_true(strlen(e->key) > 0 && strlen(e->rack_key) > 0 && strlen(e->doc) > 0);
        assert_true(e->flags == GS_PARAM_FIXED || e->flags == GS_PARAM_TUNABLE || e->flags == GS_PARAM_GEAR_ONLY);
        check_options(e);
        if (e->kind == GS_PARAM_OPTION || e->kind == GS_PARAM_BOOL || e->kind == GS_PARAM_INT ||
            e->kind == GS_PARAM_COUNT || e->kind == GS_PARAM_GROUP) {
            assert_string_equal(e->gear_unit, "");
            assert_string_equal(e->rack_unit, "");
        }
        if (e->kind == GS_PARAM_TABLE || e->kind == GS_PARAM_MATRIX) {
            const gs_param_info *c = find(table, n, e->count);
            assert_non_null(c);
            assert_int_equal(c->kind, GS_PARAM_COUNT);
            assert_true(c < e); /* the count comes first */
        }
        if (e->kind == GS_PARAM_MATRIX) {
            const gs_param_info *c2 = find(table, n, e->count2);
            assert_non_null(c2);
            assert_int_equal(c2->kind, GS_PARAM_COUNT);
        } else {
            assert_string_equal(e->count2, "");
        }
        if (e->kind == GS_PARAM_GROUP) {
            check_table(e->members, e->member_count);
        } else {
            assert_null(e->members);
        }
    }
}

/* Keys of one rig (the rig's, the block's, the backlash's; GEAR_ONLY left
 * out of the rack rig) must be unique. */
static size_t collect_keys(const gs_param_info *table, size_t n, int rack, const char **keys, size_t k)
{
    for (size_t i = 0; i < n; ++i) {
        const gs_param_info *e = &table[i];
        if (e->kind == GS_PARAM_GROUP) {
            k = collect_keys(e->members, e->member_count, rack, keys, k);
        } else if (!(rack && e->flags == GS_PARAM_GEAR_ONLY)) {
            assert_true(k < 2 * MAX_ENTRIES);
            keys[k++] = rack ? e->rack_key : e->key;
        }
    }
    return k;
}

static void test_tables_are_consistent(void **state)
{
    (void)state;
    check_table(gs_rig_param_info, GS_RIG_PARAM_FIELDS);
    check_table(gs_simple_gear_param_info, GS_SIMPLE_GEAR_PARAM_FIELDS);
    check_table(gs_rack_pinion_param_info, GS_RACK_PINION_PARAM_FIELDS);
    for (int rack = 0; rack < 2; ++rack) {
        const char *keys[2 * MAX_ENTRIES];
        size_t k = collect_keys(gs_rig_param_info, GS_RIG_PARAM_FIELDS, rack, keys, 0);
        k = rack ? collect_keys(gs_rack_pinion_param_info, GS_RACK_PINION_PARAM_FIELDS, rack, keys, k)
                 : collect_keys(gs_simple_gear_param_info, GS_SIMPLE_GEAR_PARAM_FIELDS, rack, keys, k);
        for (size_t i = 0; i < k; ++i) {
            for (size_t j = 0; j < i; ++j) {
                if (strcmp(keys[i], keys[j]) == 0) {
                    print_error("key %s twice in the %s rig\n", keys[i], rack ? "rack" : "gear");
                }
                assert_true(strcmp(keys[i], keys[j]) != 0);
            }
        }
    }
}

/* Facts the documentation states (docs/measurement-format.md 2.1,
 * docs/physics.md 9-11), checked against the tables. */
static void test_documented_entries(void **state)
{
    (void)state;
    const gs_param_info *d = find(gs_rig_param_info, GS_RIG_PARAM_FIELDS, "driven_inertia");
    assert_non_null(d);
    assert_string_equal(d->key, "follower_inertia");
    assert_string_equal(d->rack_key, "rack_mass");
    assert_string_equal(d->gear_unit, "kg*m**2");
    assert_string_equal(d->rack_unit, "kg");
    assert_int_equal(d->offset, offsetof(gs_rig_params, driven_inertia));

    const gs_param_info *f = find(gs_rack_pinion_param_info, GS_RACK_PINION_PARAM_FIELDS, "friction_model");
    assert_non_null(f);
    assert_int_equal(f->options->count, 3);
    assert_int_equal(f->options->items[0].value, GS_FRICTION_NONE);
    assert_int_equal(f->options->items[1].value, GS_FRICTION_CONSTANT_EFFICIENCY);
    assert_int_equal(f->options->items[2].value, GS_FRICTION_TEMPERATURE_DEPENDENT_EFFICIENCY);
    assert_string_equal(f->options->items[2].name, "temperature_dependent_efficiency");
    const gs_param_info *g = find(gs_simple_gear_param_info, GS_SIMPLE_GEAR_PARAM_FIELDS, "friction_model");
    assert_non_null(g);
    assert_int_equal(g->options->count, 5);
    assert_string_equal(g->options->name, "FrictionModel");

    const gs_param_info *r = find(gs_rig_param_info, GS_RIG_PARAM_FIELDS, "ripple_mesh_phase_rad");
    assert_non_null(r);
    assert_int_equal(r->kind, GS_PARAM_ARRAY);
    assert_int_equal(r->length, 2);
    assert_string_equal(r->gear_unit, "rad");

    const gs_param_info *m = find(gs_simple_gear_param_info, GS_SIMPLE_GEAR_PARAM_FIELDS, "efficiency_matrix");
    assert_non_null(m);
    assert_int_equal(m->length, 10);
    assert_int_equal(m->columns, 10);
    assert_string_equal(m->count, "temperature_count");
    assert_string_equal(m->count2, "load_count");

    const gs_param_info *t = find(gs_rig_param_info, GS_RIG_PARAM_FIELDS, "temperature_source");
    assert_non_null(t);
    assert_int_equal(t->kind, GS_PARAM_BOOL);
    assert_string_equal(t->key, "temperature_input");
    assert_int_equal(t->options->items[1].value, GS_TEMPERATURE_FROM_INPUT);
    assert_int_equal(t->size, sizeof(gs_temperature_source));

    const gs_param_info *b = find(gs_backlash_param_info, GS_BACKLASH_PARAM_FIELDS, "base_radius_m");
    assert_non_null(b);
    assert_int_equal(b->flags, GS_PARAM_GEAR_ONLY);
    assert_string_equal(b->key, "base_radius");
}

/* The value written through the table into element k of a member. */
static double written(const char *member, size_t k)
{
    double v = 0.0;
    for (size_t i = 0; i < GS_RIG_PARAM_FIELDS; ++i) {
        const gs_param_info *e = &gs_rig_param_info[i];
        if (e->kind == GS_PARAM_REAL || e->kind == GS_PARAM_ARRAY) {
            for (size_t j = 0; j < e->length; ++j) {
                v += 1.0;
                if (strcmp(e->member, member) == 0 && j == k) {
                    return v;
                }
            }
        }
    }
    fail_msg("%s[%zu] is not a real of gs_rig_param_info", member, k);
    return 0.0;
}

/* Writing every gs_real of the rig params through the table (offset,
 * length) and reading the members by name gives back what was written. */
static void test_generic_access(void **state)
{
    (void)state;
    gs_rig_params p;
    memset(&p, 0, sizeof p);
    double next = 1.0;
    for (size_t i = 0; i < GS_RIG_PARAM_FIELDS; ++i) {
        const gs_param_info *e = &gs_rig_param_info[i];
        if (e->kind == GS_PARAM_REAL || e->kind == GS_PARAM_ARRAY) {
            for (size_t k = 0; k < e->length; ++k) {
                const gs_real v = (gs_real)next;
                next += 1.0;
                memcpy((unsigned char *)&p + e->offset + k * sizeof(gs_real), &v, sizeof v);
            }
        }
    }
    assert_true(is_zero((double)p.dt_s - written("dt_s", 0)));
    assert_true(is_zero((double)p.base_inertia_kg_m2 - written("base_inertia_kg_m2", 0)));
    assert_true(is_zero((double)p.driven_inertia - written("driven_inertia", 0)));
    assert_true(is_zero((double)p.load_offset - written("load_offset", 0)));
    assert_true(is_zero((double)p.ripple_revolution_amplitude_Nm[1] - written("ripple_revolution_amplitude_Nm", 1)));
    assert_true(is_zero((double)p.ripple_mesh_phase_rad[0] - written("ripple_mesh_phase_rad", 0)));
    assert_true(is_zero((double)p.ripple_mesh_phase_rad[1] - written("ripple_mesh_phase_rad", 1)));
    /* ints and enums are untouched */
    assert_int_equal(p.contact_substeps, 0);
    assert_int_equal(p.ripple_mesh_teeth, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tables_cover_their_structs),
        cmocka_unit_test(test_checker_finds_doctored_tables),
        cmocka_unit_test(test_tables_are_consistent),
        cmocka_unit_test(test_documented_entries),
        cmocka_unit_test(test_generic_access),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
