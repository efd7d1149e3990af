/*
 * gs_fmu_modeldescription.c - writes modelDescription.xml of a rig FMU, or the
 * Markdown variable table of docs/fmu.md, from the variable tables of
 * gs_fmu_model.c (start values are the C defaults).
 *
 * Usage: gs_fmu_modeldescription xml gear|rack OUTPUT.xml
 *        gs_fmu_modeldescription markdown gear|rack   (to stdout)
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gs_fmu_model.h"

/* Shortest decimal that reads back to the same double; plain notation (300,
 * not 3e+02) for magnitudes in [1, 1e6). */
static void format_real(char *buf, size_t size, double x)
{
    int digits = 0; /* decimal exponent of |x| when 1 <= |x| < 1e6 */
    for (double y = x < 0.0 ? -x : x; y >= 10.0 && y < 1e6; y /= 10.0) {
        ++digits;
    }
    for (int precision = 1; precision <= 17; ++precision) {
        const int p = precision > digits ? precision : digits + 1;
        (void)snprintf(buf, size, "%.*g", p, x);
        const double back = strtod(buf, NULL);
        if (memcmp(&back, &x, sizeof x) == 0) {
            return;
        }
    }
}

static void put_escaped(FILE *f, const char *s)
{
    for (; s != NULL && *s != '\0'; ++s) {
        switch (*s) {
        case '&':
            fputs("&amp;", f);
            break;
        case '<':
            fputs("&lt;", f);
            break;
        case '>':
            fputs("&gt;", f);
            break;
        case '"':
            fputs("&quot;", f);
            break;
        default:
            fputc(*s, f);
            break;
        }
    }
}

/* The first variable of its enumeration type (the type is written once, with
 * that variable's description). */
static int first_of_enum_type(const gs_fmu_var *vars, size_t i)
{
    if (vars[i].type != GS_FMU_T_ENUMERATION) {
        return 0;
    }
    for (size_t k = 0; k < i; ++k) {
        if (vars[k].type == GS_FMU_T_ENUMERATION && strcmp(vars[k].enum_type, vars[i].enum_type) == 0) {
            return 0;
        }
    }
    return 1;
}

static int unit_used(const gs_fmu_var *vars, size_t n, const char *unit)
{
    for (size_t i = 0; i < n; ++i) {
        if (vars[i].unit != NULL && strcmp(vars[i].unit, unit) == 0) {
            return 1;
        }
    }
    return 0;
}

static const void *start_base(const gs_fmu_var *v, const gs_fmu_params *params, const gs_rig_input *input)
{
    return v->region == GS_FMU_AT_PARAMS ? (const void *)params : (const void *)input;
}

static const char *causality_name(gs_fmu_causality c)
{
    switch (c) {
    case GS_FMU_C_PARAMETER:
        return "parameter";
    case GS_FMU_C_INPUT:
        return "input";
    case GS_FMU_C_OUTPUT:
        return "output";
    }
    return "?";
}

static const char *variability_name(gs_fmu_variability v)
{
    switch (v) {
    case GS_FMU_V_FIXED:
        return "fixed";
    case GS_FMU_V_TUNABLE:
        return "tunable";
    case GS_FMU_V_CONTINUOUS:
        return "continuous";
    }
    return "?";
}

static int write_xml(gs_fmu_rig rig, const char *path)
{
    gs_fmu_var vars[GS_FMU_MAX_VARS];
    const size_t n = gs_fmu_variables(rig, vars, GS_FMU_MAX_VARS);
    if (n == 0) {
        fprintf(stderr, "gs_fmu_modeldescription: variable table exceeds %d entries\n", GS_FMU_MAX_VARS);
        return 1;
    }
    gs_fmu_params params;
    gs_rig_input input;
    gs_fmu_defaults(&params, &input);
    char guid[GS_FMU_GUID_SIZE];
    gs_fmu_guid(rig, guid);
    char num[64];

    FILE *f = fopen(path, "w");
    if (f == NULL) {
        perror(path);
        return 1;
    }
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    fprintf(f, "<fmiModelDescription\n  fmiVersion=\"2.0\"\n  modelName=\"%s\"\n  guid=\"%s\"\n  description=\"",
            gs_fmu_model_name(rig), guid);
    put_escaped(f, gs_fmu_model_description(rig));
    fprintf(f,
            "\"\n  author=\"gearsim\"\n  version=\"%s\"\n  generationTool=\"gearsim gs_fmu_modeldescription\"\n"
            "  variableNamingConvention=\"structured\"\n  numberOfEventIndicators=\"0\">\n",
            GS_VERSION_STRING);
    fprintf(f,
            "  <CoSimulation\n    modelIdentifier=\"%s\"\n"
            "    needsExecutionTool=\"false\"\n"
            "    canHandleVariableCommunicationStepSize=\"true\"\n"
            "    canInterpolateInputs=\"false\"\n"
            "    maxOutputDerivativeOrder=\"0\"\n"
            "    canRunAsynchronuously=\"false\"\n"
            "    canBeInstantiatedOnlyOncePerProcess=\"false\"\n"
            "    canNotUseMemoryManagementFunctions=\"false\"\n"
            "    canGetAndSetFMUstate=\"true\"\n"
            "    canSerializeFMUstate=\"true\"\n"
            "    providesDirectionalDerivative=\"false\"/>\n",
            gs_fmu_model_identifier(rig));

    size_t nunits;
    const gs_fmu_unit *units = gs_fmu_units(&nunits);
    fprintf(f, "  <UnitDefinitions>\n");
    for (size_t i = 0; i < nunits; ++i) {
        const gs_fmu_unit *u = &units[i];
        if (!unit_used(vars, n, u->name)) {
            continue;
        }
        fprintf(f, "    <Unit name=\"");
        put_escaped(f, u->name);
        fprintf(f, "\">\n      <BaseUnit");
        const char *names[5] = {"kg", "m", "s", "K", "rad"};
        const int exps[5] = {u->kg, u->m, u->s, u->K, u->rad};
        for (int k = 0; k < 5; ++k) {
            if (exps[k] != 0) {
                fprintf(f, " %s=\"%d\"", names[k], exps[k]);
            }
        }
        fprintf(f, "/>\n");
        if (u->display_name != NULL) {
            fprintf(f, "      <DisplayUnit name=\"");
            put_escaped(f, u->display_name);
            format_real(num, sizeof num, u->display_factor);
            fprintf(f, "\" factor=\"%s\"", num);
            format_real(num, sizeof num, u->display_offset);
            fprintf(f, " offset=\"%s\"/>\n", num);
        }
        fprintf(f, "    </Unit>\n");
    }
    fprintf(f, "  </UnitDefinitions>\n");

    fprintf(f, "  <TypeDefinitions>\n");
    for (size_t i = 0; i < n; ++i) {
        if (!first_of_enum_type(vars, i)) {
            continue;
        }
        const gs_param_options *o = vars[i].options;
        fprintf(f, "    <SimpleType name=\"%s\" description=\"", o->name);
        put_escaped(f, vars[i].description);
        fprintf(f, "\">\n      <Enumeration>\n");
        for (size_t k = 0; k < o->count; ++k) {
            fprintf(f, "        <Item name=\"%s\" value=\"%d\" description=\"", o->items[k].name, o->items[k].value);
            put_escaped(f, o->items[k].doc);
            fprintf(f, "\"/>\n");
        }
        fprintf(f, "      </Enumeration>\n    </SimpleType>\n");
    }
    fprintf(f, "  </TypeDefinitions>\n");

    fprintf(f, "  <LogCategories>\n"
               "    <Category name=\"logStatusError\" description=\"errors: refused parameter values, bad "
               "step sizes, calls out of order (always reported)\"/>\n"
               "    <Category name=\"logStatusWarning\" description=\"warnings (always reported)\"/>\n"
               "    <Category name=\"logInfo\" description=\"information, with debug logging on\"/>\n"
               "  </LogCategories>\n");

    format_real(num, sizeof num, (double)params.rig.dt_s);
    fprintf(f, "  <DefaultExperiment startTime=\"0\" stopTime=\"1\" stepSize=\"%s\"/>\n", num);

    fprintf(f, "  <ModelVariables>\n");
    for (size_t i = 0; i < n; ++i) {
        const gs_fmu_var *v = &vars[i];
        fprintf(f, "    <!-- %zu -->\n    <ScalarVariable name=\"", i + 1);
        put_escaped(f, v->name);
        fprintf(f, "\" valueReference=\"%zu\" description=\"", i);
        put_escaped(f, v->description);
        fprintf(f, "\" causality=\"%s\" variability=\"%s\"", causality_name(v->causality),
                variability_name(v->variability));
        if (v->causality == GS_FMU_C_PARAMETER) {
            fprintf(f, " initial=\"exact\"");
        }
        fprintf(f, ">\n      ");
        const void *base = start_base(v, &params, &input);
        switch (v->type) {
        case GS_FMU_T_REAL:
            fprintf(f, "<Real");
            if (v->unit != NULL) {
                fprintf(f, " unit=\"");
                put_escaped(f, v->unit);
                fprintf(f, "\"");
            }
            if (v->causality != GS_FMU_C_OUTPUT) {
                format_real(num, sizeof num, gs_fmu_read_real(v, base));
                fprintf(f, " start=\"%s\"", num);
            }
            fprintf(f, "/>\n");
            break;
        case GS_FMU_T_INTEGER:
            fprintf(f, "<Integer start=\"%d\"/>\n", gs_fmu_read_int(v, base));
            break;
        case GS_FMU_T_BOOLEAN:
            fprintf(f, "<Boolean start=\"%s\"/>\n", gs_fmu_read_int(v, base) != 0 ? "true" : "false");
            break;
        case GS_FMU_T_ENUMERATION:
            fprintf(f, "<Enumeration declaredType=\"%s\" start=\"%d\"/>\n", v->enum_type, gs_fmu_read_int(v, base));
            break;
        }
        fprintf(f, "    </ScalarVariable>\n");
    }
    fprintf(f, "  </ModelVariables>\n");

    /* every output has initial="calculated" (the default), which makes it an
     * initial unknown as well; neither list declares dependencies */
    static const char *const unknown_lists[] = {"Outputs", "InitialUnknowns"};
    fprintf(f, "  <ModelStructure>\n");
    for (size_t l = 0; l < sizeof unknown_lists / sizeof unknown_lists[0]; ++l) {
        fprintf(f, "    <%s>\n", unknown_lists[l]);
        for (size_t i = 0; i < n; ++i) {
            if (vars[i].causality == GS_FMU_C_OUTPUT) {
                fprintf(f, "      <Unknown index=\"%zu\"/>\n", i + 1);
            }
        }
        fprintf(f, "    </%s>\n", unknown_lists[l]);
    }
    fprintf(f, "  </ModelStructure>\n</fmiModelDescription>\n");
    if (fclose(f) != 0) {
        perror(path);
        return 1;
    }
    return 0;
}

/* ---- Markdown: one row per variable, tables collapsed to one row */

static int same_table(const gs_fmu_var *a, const gs_fmu_var *b)
{
    return a->base_name == b->base_name || strcmp(a->base_name, b->base_name) == 0;
}

static void markdown_start(const gs_fmu_var *vars, size_t first, size_t count, const gs_fmu_params *params,
                           const gs_rig_input *input, char *buf, size_t size)
{
    char num[64];
    const gs_fmu_var *v = &vars[first];
    const void *base = start_base(v, params, input);
    buf[0] = '\0';
    if (v->causality == GS_FMU_C_OUTPUT) {
        return;
    }
    if (count == 1 && strchr(v->name, '[') == NULL) {
        switch (v->type) {
        case GS_FMU_T_REAL:
            format_real(buf, size, gs_fmu_read_real(v, base));
            break;
        case GS_FMU_T_INTEGER:
            (void)snprintf(buf, size, "%d", gs_fmu_read_int(v, base));
            break;
        case GS_FMU_T_BOOLEAN:
            (void)snprintf(buf, size, "%s", gs_fmu_read_int(v, base) ? "true" : "false");
            break;
        case GS_FMU_T_ENUMERATION: {
            const int value = gs_fmu_read_int(v, base);
            const char *item = "?";
            for (size_t k = 0; k < v->options->count; ++k) {
                if (v->options->items[k].value == value) {
                    item = v->options->items[k].name;
                }
            }
            (void)snprintf(buf, size, "%d (%s)", value, item);
            break;
        }
        }
        return;
    }
    /* a table: its non-zero entries */
    size_t used = 0;
    int listed = 0;
    for (size_t i = 0; i < count && used + 40 < size; ++i) {
        const double x = gs_fmu_read_real(&vars[first + i], base);
        if (!(x < 0.0 || x > 0.0)) {
            continue;
        }
        format_real(num, sizeof num, x);
        used += (size_t)snprintf(buf + used, size - used, "%s%s=%s", listed ? ", " : "",
                                 strchr(vars[first + i].name, '['), num);
        listed = 1;
    }
    (void)snprintf(buf + used, size - used, "%s", listed ? "; others 0" : "all 0");
}

static int write_markdown(gs_fmu_rig rig)
{
    gs_fmu_var vars[GS_FMU_MAX_VARS];
    const size_t n = gs_fmu_variables(rig, vars, GS_FMU_MAX_VARS);
    gs_fmu_params params;
    gs_rig_input input;
    gs_fmu_defaults(&params, &input);
    char start[2048];
    printf("| value ref. | name | causality | variability | type | unit | start | description |\n");
    printf("|---|---|---|---|---|---|---|---|\n");
    size_t i = 0;
    while (i < n) {
        size_t count = 1;
        while (i + count < n && strchr(vars[i].name, '[') != NULL && same_table(&vars[i], &vars[i + count])) {
            ++count;
        }
        const gs_fmu_var *v = &vars[i];
        markdown_start(vars, i, count, &params, &input, start, sizeof start);
        char name[96];
        if (count > 1) {
            (void)snprintf(name, sizeof name, "%s%s..%s", v->base_name, strchr(v->name, '['),
                           strchr(vars[i + count - 1].name, '['));
            printf("| %zu..%zu ", i, i + count - 1);
        } else {
            (void)snprintf(name, sizeof name, "%s", v->name);
            printf("| %zu ", i);
        }
        const char *type = v->type == GS_FMU_T_ENUMERATION ? v->enum_type : gs_fmu_type_name(v->type);
        printf("| `%s` | %s | %s | %s | %s | %s | %s |\n", name, causality_name(v->causality),
               variability_name(v->variability), type,
               v->unit != NULL ? v->unit : (v->type == GS_FMU_T_REAL ? "1" : ""), start, v->description);
        i += count;
    }
    printf("\nEnumerations (set and read with fmi2SetInteger / fmi2GetInteger):\n\n");
    for (size_t t = 0; t < n; ++t) {
        if (!first_of_enum_type(vars, t)) {
            continue;
        }
        const gs_param_options *o = vars[t].options;
        printf("- `%s`:", o->name);
        for (size_t k = 0; k < o->count; ++k) {
            printf("%s %d = `%s`", k > 0 ? "," : "", o->items[k].value, o->items[k].name);
        }
        printf("\n");
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc < 3 || (strcmp(argv[2], "gear") != 0 && strcmp(argv[2], "rack") != 0) ||
        (strcmp(argv[1], "xml") == 0 && argc != 4) || (strcmp(argv[1], "markdown") == 0 && argc != 3) ||
        (strcmp(argv[1], "xml") != 0 && strcmp(argv[1], "markdown") != 0)) {
        fprintf(stderr, "usage: %s xml gear|rack OUTPUT.xml\n       %s markdown gear|rack\n", argv[0], argv[0]);
        return 2;
    }
    const gs_fmu_rig rig = strcmp(argv[2], "gear") == 0 ? GS_FMU_RIG_GEAR : GS_FMU_RIG_RACK;
    return strcmp(argv[1], "xml") == 0 ? write_xml(rig, argv[3]) : write_markdown(rig);
}
