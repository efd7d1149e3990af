/*
 * gs_fmu.c - FMI 2.0 co-simulation interface over one gearsim rig.
 *
 * Compiled once per rig with GS_FMU_RIG_KIND = 0 (gear rig) or 1 (rack rig)
 * into binaries/<platform>/<modelIdentifier>.so; only the fmi2* functions are
 * exported (the core is built with -fvisibility=hidden).
 *
 * - Parameters live in the C params structs (gs_fmu_model.h); they are
 *   validated by gs_rig_init_gear / gs_rig_init_rack in
 *   fmi2ExitInitializationMode. A refused value returns fmi2Error, logs the
 *   parameter named by gs_error and leaves the instance in initialisation
 *   mode so that the value can be corrected.
 * - The rig is its constants (gs_rig_consts: derived by init from the
 *   parameters, read-only afterwards) and its state (gs_rig_state).
 * - Tunable parameters set in step mode are validated at once (the new values
 *   go through the rig init into new constants; the running state is kept and
 *   stepped on with them); a refused value leaves every variable of the call
 *   unchanged.
 * - fmi2DoStep runs h/dt fixed steps of dt with the inputs held; h must be a
 *   whole multiple of dt. Outputs are those of the last internal step.
 * - The FMU state is the plain-data struct fmu_data (parameters, inputs,
 *   outputs and a copy of the gs_rig_state alone). The constants are not part
 *   of it: they follow from the parameters, and are derived again only when a
 *   restored state carries other parameters than the running ones.
 *   Serialisation writes fmu_data after a header; reading it back validates
 *   the parameters through the rig init.
 */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fmi2Functions.h"
#include "gs_fmu_model.h"

#ifndef GS_FMU_RIG_KIND
#error "compile with -DGS_FMU_RIG_KIND=0 (gear rig) or -DGS_FMU_RIG_KIND=1 (rack rig)"
#endif
#define THIS_RIG ((gs_fmu_rig)GS_FMU_RIG_KIND)

enum { MODE_INSTANTIATED = 1 << 0, MODE_INITIALIZATION = 1 << 1, MODE_STEP = 1 << 2, MODE_TERMINATED = 1 << 3 };
#define MODE_ANY (MODE_INSTANTIATED | MODE_INITIALIZATION | MODE_STEP | MODE_TERMINATED)

/* Relative tolerance on h/dt and on the communication time. */
#define STEP_RATIO_TOLERANCE 1e-6
#define MAX_STEPS_PER_CALL   1e12

/* Everything an FMU state holds: plain data, no pointers. */
typedef struct {
    int mode;
    int rig_ready; /* rig initialised from params */
    gs_fmu_params params;
    gs_rig_input input;
    gs_rig_output output;
    gs_rig_state state; /* the rig's state: what a step updates */
    double start_time;
    long long steps; /* internal steps since start_time */
} fmu_data;

typedef struct {
    fmu_data d;
    /* the rig's constants, derived from consts_params (valid when
     * consts_ready); outside fmu_data, so that an FMU state does not copy them */
    gs_rig_consts consts;
    gs_fmu_params consts_params;
    int consts_ready;
    size_t nvars;
    gs_fmu_var vars[GS_FMU_MAX_VARS];
    fmi2CallbackLogger logger;
    fmi2CallbackAllocateMemory allocate;
    fmi2CallbackFreeMemory release;
    fmi2ComponentEnvironment env;
    char *name;
    int logging_on;
    int log_info; /* category "logInfo" enabled */
    char guid[GS_FMU_GUID_SIZE];
} fmu;

static const char *const log_categories[] = {"logStatusError", "logStatusWarning", "logInfo"};

/* ---- logging: errors and warnings always, logInfo only with debug logging on */

static void emit(fmi2CallbackLogger logger, fmi2ComponentEnvironment env, const char *name, fmi2Status status,
                 const char *category, const char *fmt, va_list ap)
{
    char raw[1024];
    char escaped[2048];
    if (logger == NULL) {
        return;
    }
    (void)vsnprintf(raw, sizeof raw, fmt, ap);
    /* the master may treat the message as a printf format */
    size_t j = 0;
    for (size_t i = 0; raw[i] != '\0' && j + 2 < sizeof escaped; ++i) {
        if (raw[i] == '%') {
            escaped[j++] = '%';
        }
        escaped[j++] = raw[i];
    }
    escaped[j] = '\0';
    logger(env, name != NULL ? name : "", status, category, escaped);
}

#if defined(__GNUC__)
#define GS_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define GS_PRINTF(a, b)
#endif

static void log_status(const fmu *c, fmi2Status status, const char *fmt, ...) GS_PRINTF(3, 4);
static void log_status(const fmu *c, fmi2Status status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    emit(c->logger, c->env, c->name, status, status == fmi2Warning ? "logStatusWarning" : "logStatusError", fmt, ap);
    va_end(ap);
}

static void log_info(const fmu *c, const char *fmt, ...) GS_PRINTF(2, 3);
static void log_info(const fmu *c, const char *fmt, ...)
{
    if (!c->logging_on || !c->log_info) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    emit(c->logger, c->env, c->name, fmi2OK, "logInfo", fmt, ap);
    va_end(ap);
}

static void log_early(const fmi2CallbackFunctions *functions, const char *name, const char *fmt, ...) GS_PRINTF(3, 4);
static void log_early(const fmi2CallbackFunctions *functions, const char *name, const char *fmt, ...)
{
    if (functions == NULL) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    emit(functions->logger, functions->componentEnvironment, name, fmi2Error, "logStatusError", fmt, ap);
    va_end(ap);
}

static const char *mode_name(int mode)
{
    switch (mode) {
    case MODE_INSTANTIATED:
        return "instantiated";
    case MODE_INITIALIZATION:
        return "initialization mode";
    case MODE_STEP:
        return "step mode";
    case MODE_TERMINATED:
        return "terminated";
    default:
        return "unknown";
    }
}

static int allowed(const fmu *c, const char *function, int modes)
{
    if ((c->d.mode & modes) != 0) {
        return 1;
    }
    log_status(c, fmi2Error, "%s: not allowed in %s", function, mode_name(c->d.mode));
    return 0;
}

/* ---- helpers */

/* dt is a fixed parameter: once the rig is initialised its dt is the same
 * value, and before that steps is 0. */
static double current_time(const fmu_data *d)
{
    return d->start_time + (double)d->steps * (double)d->params.rig.dt_s;
}

/* The data of a newly instantiated or reset FMU: start values, no rig yet. */
static void instantiated_data(fmu_data *d)
{
    memset(d, 0, sizeof *d);
    gs_fmu_defaults(&d->params, &d->input);
    d->mode = MODE_INSTANTIATED;
}

static void *region_of(fmu_data *d, gs_fmu_region region)
{
    switch (region) {
    case GS_FMU_AT_PARAMS:
        return &d->params;
    case GS_FMU_AT_INPUT:
        return &d->input;
    case GS_FMU_AT_OUTPUT:
        return &d->output;
    }
    return NULL;
}

/* "efficiency_const = 1.5" when the failing parameter is one scalar variable. */
static void describe_value(const fmu *c, const fmu_data *d, const char *parameter, char *buf, size_t size)
{
    buf[0] = '\0';
    for (size_t i = 0; i < c->nvars; ++i) {
        const gs_fmu_var *v = &c->vars[i];
        if (v->causality == GS_FMU_C_PARAMETER && strcmp(v->name, parameter) == 0) {
            if (v->type == GS_FMU_T_REAL) {
                (void)snprintf(buf, size, " (value %.17g)", gs_fmu_read_real(v, &d->params));
            } else {
                (void)snprintf(buf, size, " (value %d)", gs_fmu_read_int(v, &d->params));
            }
            return;
        }
    }
    for (size_t i = 0; i < c->nvars; ++i) {
        if (c->vars[i].causality == GS_FMU_C_PARAMETER && strcmp(c->vars[i].base_name, parameter) == 0) {
            (void)snprintf(buf, size, " (table %s[...])", parameter);
            return;
        }
    }
}

static void report_parameter_error(const fmu *c, const fmu_data *d, const char *function, const gs_error *err)
{
    char value[96];
    const char *parameter = err->parameter != NULL ? err->parameter : "";
    describe_value(c, d, parameter, value, sizeof value);
    log_status(c, fmi2Error, "%s: parameter \"%s\" rejected%s: %s (gearsim status %d)", function, parameter, value,
               err->message != NULL ? err->message : gs_status_str(err->status), (int)err->status);
}

/* Validates with->params through the rig init and derives their constants
 * into *consts; a refused value is logged and leaves *consts unchanged (the
 * init leaves its outputs unchanged on failure, rig.h). The initial state
 * that init also fills is dropped: the running state is kept (re-tuning is
 * new constants stepping the old state). */
static int derive_consts(const fmu *c, const fmu_data *with, gs_rig_consts *consts, const char *function)
{
    gs_rig_state initial;
    gs_error err;
    if (gs_fmu_init_rig(THIS_RIG, &with->params, consts, &initial, &err) != GS_OK) {
        report_parameter_error(c, with, function, &err);
        return 0;
    }
    return 1;
}

/* Makes the constants of with->params the ones in use (derive_consts into
 * c->consts); a refused value leaves them unchanged. */
static int apply_consts(fmu *c, const fmu_data *with, const char *function)
{
    if (!derive_consts(c, with, &c->consts, function)) {
        return 0;
    }
    c->consts_params = with->params;
    c->consts_ready = 1;
    return 1;
}

/* Makes the constants follow the parameters of c->d, deriving them again
 * only when those parameters changed. */
static int sync_consts(fmu *c, const char *function)
{
    if (!c->d.rig_ready || (c->consts_ready && memcmp(&c->consts_params, &c->d.params, sizeof c->consts_params) == 0)) {
        return 1;
    }
    return apply_consts(c, &c->d, function);
}

/* Outputs before the first step: the initial state, zero torques and powers. */
static void initial_outputs(fmu_data *d, const gs_rig_consts *consts)
{
    const gs_rig_state *st = &d->state;
    gs_rig_output *o = &d->output;
    gs_rig_info info;
    gs_rig_get_info(consts, &info);
    memset(o, 0, sizeof *o);
    if (d->params.rig.base_drive == GS_BASE_SPEED_DRIVEN) {
        /* the first step takes the input speed with teeth moving together */
        o->base_speed = d->input.base_speed;
        o->follower_speed = info.follower_per_base * d->input.base_speed;
    } else {
        o->base_torque = d->input.base_torque;
        o->base_speed = st->base_speed;
        o->follower_speed = st->follower_speed;
    }
    o->base_angle = st->base_angle;
    o->follower_position = st->follower_position;
    o->temperature = d->params.rig.temperature_source == GS_TEMPERATURE_FROM_INPUT ? d->input.measured_temperature
                                                                                   : st->block.temperature;
    o->backlash_position = st->block.backlash_position;
}

/* ---- common functions */

const char *fmi2GetTypesPlatform(void)
{
    return fmi2TypesPlatform;
}

const char *fmi2GetVersion(void)
{
    return fmi2Version;
}

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    fmu *c = (fmu *)comp;
    if (c == NULL) {
        return fmi2Error;
    }
    c->logging_on = loggingOn != fmi2False;
    if (nCategories == 0) {
        c->log_info = 1;
        return fmi2OK;
    }
    if (categories == NULL) {
        log_status(c, fmi2Error, "fmi2SetDebugLogging: categories is NULL");
        return fmi2Error;
    }
    int info = 0;
    for (size_t i = 0; i < nCategories; ++i) {
        int known = 0;
        for (size_t k = 0; k < sizeof log_categories / sizeof log_categories[0]; ++k) {
            if (categories[i] != NULL && strcmp(categories[i], log_categories[k]) == 0) {
                known = 1;
                info |= strcmp(log_categories[k], "logInfo") == 0;
            }
        }
        if (!known) {
            log_status(c, fmi2Error, "fmi2SetDebugLogging: unknown log category \"%s\"",
                       categories[i] != NULL ? categories[i] : "(null)");
            return fmi2Error;
        }
    }
    c->log_info = info; /* errors and warnings are reported whatever the categories */
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL || functions->allocateMemory == NULL || functions->freeMemory == NULL) {
        log_early(functions, instanceName, "fmi2Instantiate: allocateMemory and freeMemory callbacks are required");
        return NULL;
    }
    if (instanceName == NULL || instanceName[0] == '\0') {
        log_early(functions, "", "fmi2Instantiate: missing instance name");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        log_early(functions, instanceName, "fmi2Instantiate: %s supports co-simulation only",
                  gs_fmu_model_identifier(THIS_RIG));
        return NULL;
    }
    char guid[GS_FMU_GUID_SIZE];
    gs_fmu_guid(THIS_RIG, guid);
    if (fmuGUID == NULL || strcmp(fmuGUID, guid) != 0) {
        log_early(functions, instanceName, "fmi2Instantiate: GUID %s does not match the binary's %s",
                  fmuGUID != NULL ? fmuGUID : "(null)", guid);
        return NULL;
    }
    fmu *c = (fmu *)functions->allocateMemory(1, sizeof(fmu));
    if (c == NULL) {
        log_early(functions, instanceName, "fmi2Instantiate: out of memory");
        return NULL;
    }
    const size_t len = strlen(instanceName);
    c->name = (char *)functions->allocateMemory(len + 1, 1);
    if (c->name == NULL) {
        functions->freeMemory(c);
        log_early(functions, instanceName, "fmi2Instantiate: out of memory");
        return NULL;
    }
    memcpy(c->name, instanceName, len + 1);
    c->logger = functions->logger;
    c->allocate = functions->allocateMemory;
    c->release = functions->freeMemory;
    c->env = functions->componentEnvironment;
    c->logging_on = loggingOn != fmi2False;
    c->log_info = 1;
    memcpy(c->guid, guid, sizeof guid);
    c->nvars = gs_fmu_variables(THIS_RIG, c->vars, GS_FMU_MAX_VARS);
    instantiated_data(&c->d);
    log_info(c, "fmi2Instantiate: %s, gearsim %s, %zu variables", gs_fmu_model_identifier(THIS_RIG), GS_VERSION_STRING,
             c->nvars);
    return c;
}

void fmi2FreeInstance(fmi2Component comp)
{
    fmu *c = (fmu *)comp;
    if (c == NULL) {
        return;
    }
    fmi2CallbackFreeMemory release = c->release;
    release(c->name);
    release(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean toleranceDefined, fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    fmu *c = (fmu *)comp;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (c == NULL || !allowed(c, "fmi2SetupExperiment", MODE_INSTANTIATED)) {
        return fmi2Error;
    }
    if (!isfinite(startTime)) {
        log_status(c, fmi2Error, "fmi2SetupExperiment: start time must be finite");
        return fmi2Error;
    }
    c->d.start_time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp)
{
    fmu *c = (fmu *)comp;
    if (c == NULL || !allowed(c, "fmi2EnterInitializationMode", MODE_INSTANTIATED)) {
        return fmi2Error;
    }
    c->d.mode = MODE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp)
{
    fmu *c = (fmu *)comp;
    if (c == NULL || !allowed(c, "fmi2ExitInitializationMode", MODE_INITIALIZATION)) {
        return fmi2Error;
    }
    gs_error err;
    if (gs_fmu_init_rig(THIS_RIG, &c->d.params, &c->consts, &c->d.state, &err) != GS_OK) {
        report_parameter_error(c, &c->d, "fmi2ExitInitializationMode", &err);
        return fmi2Error; /* still in initialization mode: the value can be corrected */
    }
    c->consts_params = c->d.params;
    c->consts_ready = 1;
    c->d.rig_ready = 1;
    c->d.steps = 0;
    initial_outputs(&c->d, &c->consts);
    c->d.mode = MODE_STEP;
    gs_rig_info info;
    gs_rig_get_info(&c->consts, &info);
    log_info(c, "fmi2ExitInitializationMode: rig initialised, dt = %.17g s, %d contact sub-steps",
             (double)c->d.params.rig.dt_s, info.contact_substeps);
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component comp)
{
    fmu *c = (fmu *)comp;
    if (c == NULL || !allowed(c, "fmi2Terminate", MODE_INITIALIZATION | MODE_STEP)) {
        return fmi2Error;
    }
    c->d.mode = MODE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp)
{
    fmu *c = (fmu *)comp;
    if (c == NULL || !allowed(c, "fmi2Reset", MODE_ANY)) {
        return fmi2Error;
    }
    instantiated_data(&c->d);
    c->consts_ready = 0;
    return fmi2OK;
}

/* ---- get and set */

/* An fmi2*Integer call also serves the Enumeration variables. */
static int check_vr(const fmu *c, const char *function, fmi2ValueReference vr, gs_fmu_type type)
{
    if (vr >= c->nvars) {
        log_status(c, fmi2Error, "%s: unknown value reference %u", function, (unsigned)vr);
        return 0;
    }
    const gs_fmu_type t = c->vars[vr].type;
    const int ok = t == type || (type == GS_FMU_T_INTEGER && t == GS_FMU_T_ENUMERATION);
    if (!ok) {
        log_status(c, fmi2Error, "%s: variable \"%s\" (value reference %u) is of type %s", function, c->vars[vr].name,
                   (unsigned)vr, gs_fmu_type_name(t));
        return 0;
    }
    return 1;
}

static fmi2Status get_values(fmu *c, const char *function, gs_fmu_type type, const fmi2ValueReference vr[], size_t nvr,
                             fmi2Real *reals, fmi2Integer *ints)
{
    if (c == NULL || !allowed(c, function, MODE_ANY)) {
        return fmi2Error;
    }
    if (nvr > 0 && (vr == NULL || (reals == NULL && ints == NULL))) {
        log_status(c, fmi2Error, "%s: NULL argument", function);
        return fmi2Error;
    }
    for (size_t i = 0; i < nvr; ++i) {
        if (!check_vr(c, function, vr[i], type)) {
            return fmi2Error;
        }
        const gs_fmu_var *v = &c->vars[vr[i]];
        const void *base = region_of(&c->d, v->region);
        if (reals != NULL) {
            reals[i] = gs_fmu_read_real(v, base);
        } else if (type == GS_FMU_T_BOOLEAN) {
            ints[i] = gs_fmu_read_int(v, base) != 0 ? fmi2True : fmi2False;
        } else {
            ints[i] = gs_fmu_read_int(v, base);
        }
    }
    return fmi2OK;
}

/* Stages every value of the call; commits all of them, or none on error. */
static fmi2Status set_values(fmu *c, const char *function, gs_fmu_type type, const fmi2ValueReference vr[], size_t nvr,
                             const fmi2Real *reals, const fmi2Integer *ints)
{
    if (c == NULL || !allowed(c, function, MODE_INSTANTIATED | MODE_INITIALIZATION | MODE_STEP)) {
        return fmi2Error;
    }
    if (nvr > 0 && (vr == NULL || (reals == NULL && ints == NULL))) {
        log_status(c, fmi2Error, "%s: NULL argument", function);
        return fmi2Error;
    }
    fmu_data staged;
    memcpy(&staged.params, &c->d.params, sizeof staged.params);
    memcpy(&staged.input, &c->d.input, sizeof staged.input);
    int parameter_set = 0;
    for (size_t i = 0; i < nvr; ++i) {
        if (!check_vr(c, function, vr[i], type)) {
            return fmi2Error;
        }
        const gs_fmu_var *v = &c->vars[vr[i]];
        if (v->causality == GS_FMU_C_OUTPUT) {
            log_status(c, fmi2Error, "%s: \"%s\" is an output and cannot be set", function, v->name);
            return fmi2Error;
        }
        if (v->causality == GS_FMU_C_PARAMETER) {
            if (v->variability == GS_FMU_V_FIXED && c->d.mode == MODE_STEP) {
                log_status(c, fmi2Error, "%s: \"%s\" is a fixed parameter and cannot change after initialisation",
                           function, v->name);
                return fmi2Error;
            }
            parameter_set = 1;
        }
        void *base = region_of(&staged, v->region);
        if (reals != NULL) {
            if (v->causality == GS_FMU_C_INPUT && !isfinite(reals[i])) {
                log_status(c, fmi2Error, "%s: input \"%s\" must be finite (value %g)", function, v->name, reals[i]);
                return fmi2Error;
            }
            gs_fmu_write_real(v, base, reals[i]);
        } else {
            gs_fmu_write_int(v, base, type == GS_FMU_T_BOOLEAN ? (ints[i] != fmi2False) : ints[i]);
        }
    }
    if (parameter_set && c->d.mode == MODE_STEP && c->d.rig_ready &&
        memcmp(&staged.params, &c->d.params, sizeof staged.params) != 0) {
        /* a tunable parameter of a running rig: validate, new constants, the
         * same state */
        if (!apply_consts(c, &staged, function)) {
            return fmi2Error;
        }
        log_info(c, "%s: tunable parameters applied at t = %.17g s", function, current_time(&c->d));
    }
    memcpy(&c->d.params, &staged.params, sizeof staged.params);
    memcpy(&c->d.input, &staged.input, sizeof staged.input);
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    return get_values((fmu *)comp, "fmi2GetReal", GS_FMU_T_REAL, vr, nvr, value, NULL);
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
    return get_values((fmu *)comp, "fmi2GetInteger", GS_FMU_T_INTEGER, vr, nvr, NULL, value);
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
{
    return get_values((fmu *)comp, "fmi2GetBoolean", GS_FMU_T_BOOLEAN, vr, nvr, NULL, value);
}

/* fmi2GetString and fmi2SetString: an empty call succeeds, any other is refused. */
static fmi2Status no_string_variables(fmi2Component comp, const char *function, size_t nvr)
{
    fmu *c = (fmu *)comp;
    if (c == NULL) {
        return fmi2Error;
    }
    if (nvr > 0) {
        log_status(c, fmi2Error, "%s: the FMU has no String variables", function);
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
    (void)vr;
    (void)value;
    return no_string_variables(comp, "fmi2GetString", nvr);
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[])
{
    return set_values((fmu *)comp, "fmi2SetReal", GS_FMU_T_REAL, vr, nvr, value, NULL);
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[])
{
    return set_values((fmu *)comp, "fmi2SetInteger", GS_FMU_T_INTEGER, vr, nvr, NULL, value);
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[])
{
    return set_values((fmu *)comp, "fmi2SetBoolean", GS_FMU_T_BOOLEAN, vr, nvr, NULL, value);
}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
    (void)vr;
    (void)value;
    return no_string_variables(comp, "fmi2SetString", nvr);
}

/* ---- FMU state */

#define STATE_MAGIC       "GSFMI2S" /* 7 characters and the NUL: 8 bytes */
#define STATE_FORMAT      2u        /* 2: the rig's state alone (gs_rig_state), no constants */
#define STATE_HEADER_SIZE (8 + 4 + 4 + 8 + GS_FMU_GUID_SIZE)
#define STATE_SIZE        (STATE_HEADER_SIZE + sizeof(fmu_data))

/* Copies d into *state, allocating the state first when *state is NULL. */
static fmi2Status store_state(const fmu *c, const char *function, fmi2FMUstate *state, const fmu_data *d)
{
    if (*state == NULL) {
        *state = c->allocate(1, sizeof(fmu_data));
        if (*state == NULL) {
            log_status(c, fmi2Error, "%s: out of memory", function);
            return fmi2Error;
        }
    }
    memcpy(*state, d, sizeof *d);
    return fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *state)
{
    fmu *c = (fmu *)comp;
    if (c == NULL || !allowed(c, "fmi2GetFMUstate", MODE_ANY)) {
        return fmi2Error;
    }
    if (state == NULL) {
        log_status(c, fmi2Error, "fmi2GetFMUstate: NULL argument");
        return fmi2Error;
    }
    return store_state(c, "fmi2GetFMUstate", state, &c->d);
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state)
{
    fmu *c = (fmu *)comp;
    if (c == NULL || !allowed(c, "fmi2SetFMUstate", MODE_ANY)) {
        return fmi2Error;
    }
    if (state == NULL) {
        log_status(c, fmi2Error, "fmi2SetFMUstate: NULL state");
        return fmi2Error;
    }
    const fmu_data previous = c->d;
    memcpy(&c->d, state, sizeof(fmu_data));
    /* the constants follow the restored parameters (derived again only if
     * they differ from the running ones) */
    if (!sync_consts(c, "fmi2SetFMUstate")) {
        c->d = previous;
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *state)
{
    fmu *c = (fmu *)comp;
    if (c == NULL) {
        return fmi2Error;
    }
    if (state != NULL && *state != NULL) {
        c->release(*state);
        *state = NULL;
    }
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate state, size_t *size)
{
    fmu *c = (fmu *)comp;
    if (c == NULL) {
        return fmi2Error;
    }
    if (state == NULL || size == NULL) {
        log_status(c, fmi2Error, "fmi2SerializedFMUstateSize: NULL argument");
        return fmi2Error;
    }
    *size = STATE_SIZE;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate state, fmi2Byte serializedState[], size_t size)
{
    fmu *c = (fmu *)comp;
    if (c == NULL) {
        return fmi2Error;
    }
    if (state == NULL || serializedState == NULL || size < STATE_SIZE) {
        log_status(c, fmi2Error, "fmi2SerializeFMUstate: NULL argument or buffer smaller than %zu bytes",
                   (size_t)STATE_SIZE);
        return fmi2Error;
    }
    const uint32_t format = STATE_FORMAT;
    const uint32_t rig = (uint32_t)THIS_RIG;
    const uint64_t payload = sizeof(fmu_data);
    unsigned char *p = (unsigned char *)serializedState;
    memcpy(p, STATE_MAGIC, 8);
    memcpy(p + 8, &format, 4);
    memcpy(p + 12, &rig, 4);
    memcpy(p + 16, &payload, 8);
    memcpy(p + 24, c->guid, GS_FMU_GUID_SIZE);
    memcpy(p + STATE_HEADER_SIZE, state, sizeof(fmu_data));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *state)
{
    fmu *c = (fmu *)comp;
    if (c == NULL) {
        return fmi2Error;
    }
    if (serializedState == NULL || state == NULL) {
        log_status(c, fmi2Error, "fmi2DeSerializeFMUstate: NULL argument");
        return fmi2Error;
    }
    const unsigned char *p = (const unsigned char *)serializedState;
    uint32_t format = 0;
    uint32_t rig_kind = 0;
    uint64_t payload = 0;
    if (size == STATE_SIZE) {
        memcpy(&format, p + 8, 4);
        memcpy(&rig_kind, p + 12, 4);
        memcpy(&payload, p + 16, 8);
    }
    if (size != STATE_SIZE || memcmp(p, STATE_MAGIC, 8) != 0 || format != STATE_FORMAT ||
        rig_kind != (uint32_t)THIS_RIG || payload != sizeof(fmu_data) ||
        memcmp(p + 24, c->guid, GS_FMU_GUID_SIZE) != 0) {
        log_status(c, fmi2Error,
                   "fmi2DeSerializeFMUstate: not a serialized state of this FMU (%zu bytes, expected %zu from %s)",
                   size, (size_t)STATE_SIZE, gs_fmu_model_identifier(THIS_RIG));
        return fmi2Error;
    }
    fmu_data d;
    memcpy(&d, p + STATE_HEADER_SIZE, sizeof d);
    if ((d.mode != MODE_INSTANTIATED && d.mode != MODE_INITIALIZATION && d.mode != MODE_STEP &&
         d.mode != MODE_TERMINATED) ||
        d.steps < 0 || !isfinite(d.start_time)) {
        log_status(c, fmi2Error, "fmi2DeSerializeFMUstate: corrupt state");
        return fmi2Error;
    }
    /* the bytes carry the rig's state; its parameters must pass the rig init
     * (fmi2SetFMUstate derives the constants from them) */
    gs_rig_consts check;
    if (d.rig_ready && !derive_consts(c, &d, &check, "fmi2DeSerializeFMUstate")) {
        return fmi2Error;
    }
    return store_state(c, "fmi2DeSerializeFMUstate", state, &d);
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    fmu *c = (fmu *)comp;
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    if (c != NULL) {
        log_status(c, fmi2Error, "fmi2GetDirectionalDerivative: not provided");
    }
    return fmi2Error;
}

/* ---- co-simulation */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    fmu *c = (fmu *)comp;
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    if (c != NULL) {
        log_status(c, fmi2Error,
                   "fmi2SetRealInputDerivatives: inputs are held constant over a step "
                   "(canInterpolateInputs = false)");
    }
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    fmu *c = (fmu *)comp;
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    if (c != NULL) {
        log_status(c, fmi2Error, "fmi2GetRealOutputDerivatives: not provided (maxOutputDerivativeOrder = 0)");
    }
    return fmi2Error;
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    fmu *c = (fmu *)comp;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (c == NULL || !allowed(c, "fmi2DoStep", MODE_STEP)) {
        return fmi2Error;
    }
    const double dt = (double)c->d.params.rig.dt_s;
    const double h = communicationStepSize;
    if (!isfinite(h) || !(h > 0.0)) {
        log_status(c, fmi2Error, "fmi2DoStep: communication step size %.17g s must be finite and > 0", h);
        return fmi2Error;
    }
    const double ratio = h / dt;
    const double n = floor(ratio + 0.5);
    if (n < 1.0 || n > MAX_STEPS_PER_CALL || fabs(ratio - n) > STEP_RATIO_TOLERANCE) {
        log_status(c, fmi2Error,
                   "fmi2DoStep: communication step size %.17g s is not a whole multiple of the internal step "
                   "dt = %.17g s (h/dt = %.17g)",
                   h, dt, ratio);
        return fmi2Error;
    }
    const double now = current_time(&c->d);
    const double tolerance = STEP_RATIO_TOLERANCE * dt + 1e-12 * fabs(now);
    if (!(fabs(currentCommunicationPoint - now) <= tolerance)) {
        log_status(c, fmi2Error,
                   "fmi2DoStep: currentCommunicationPoint %.17g s differs from the FMU time %.17g s "
                   "(start time + %lld steps of dt)",
                   currentCommunicationPoint, now, c->d.steps);
        return fmi2Error;
    }
    const long long steps = (long long)n;
    for (long long k = 0; k < steps; ++k) {
        gs_rig_step(&c->consts, &c->d.state, &c->d.input, &c->d.output);
    }
    c->d.steps += steps;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component comp)
{
    fmu *c = (fmu *)comp;
    if (c != NULL) {
        log_status(c, fmi2Error, "fmi2CancelStep: fmi2DoStep never returns fmi2Pending");
    }
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value)
{
    (void)comp;
    (void)s;
    (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value)
{
    fmu *c = (fmu *)comp;
    if (c == NULL || value == NULL) {
        return fmi2Error;
    }
    if (s == fmi2LastSuccessfulTime) {
        *value = current_time(&c->d);
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)comp;
    (void)s;
    (void)value;
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *value)
{
    fmu *c = (fmu *)comp;
    if (c == NULL || value == NULL) {
        return fmi2Error;
    }
    if (s == fmi2Terminated) {
        *value = fmi2False;
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *value)
{
    (void)comp;
    (void)s;
    (void)value;
    return fmi2Discard;
}
