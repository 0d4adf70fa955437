/* The CPU check of p3trace, in C so that it is compiled for the plain x86-64 baseline.
 * The Rust code is compiled for the CPU that builds it (.cargo/config.toml: target-cpu
 * native); a check written in Rust would itself use those instructions (BMI2's shrx, AVX
 * moves) before it could say why it stops. The binary runs it before any of its own code
 * (main.rs puts it in `.preinit_array`). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* build.rs defines both: the target features the Rust code may use, separated by ", ",
 * and the target CPU it was compiled for. */
#if !defined(P3TRACE_TARGET_FEATURES) || !defined(P3TRACE_TARGET_CPU)
#error "build.rs defines P3TRACE_TARGET_FEATURES and P3TRACE_TARGET_CPU"
#endif

/* Whether the ", "-separated `list` holds `name`. */
static int listed(const char *list, const char *name) {
    size_t length = strlen(name);
    for (const char *at = strstr(list, name); at; at = strstr(at + 1, name)) {
        int starts = at == list || at[-1] == ' ';
        int ends = at[length] == '\0' || at[length] == ',';
        if (starts && ends)
            return 1;
    }
    return 0;
}

struct feature {
    const char *name; /* as Rust names it */
    int present;
};

void p3trace_check_cpu(void) {
    __builtin_cpu_init();
    /* The extensions of x86-64-v2, v3 and v4, then those a build for a newer CPU may add,
     * under Rust's names and in the order of machine.rs's list (a test there compares the
     * two); GCC's own names are in the calls. build.rs warns of a compiled feature that
     * this table lacks. */
    const struct feature features[] = {
        {"sse3", __builtin_cpu_supports("sse3")},
        {"ssse3", __builtin_cpu_supports("ssse3")},
        {"sse4.1", __builtin_cpu_supports("sse4.1")},
        {"sse4.2", __builtin_cpu_supports("sse4.2")},
        {"popcnt", __builtin_cpu_supports("popcnt")},
        {"cmpxchg16b", __builtin_cpu_supports("cmpxchg16b")},
        {"avx", __builtin_cpu_supports("avx")},
        {"avx2", __builtin_cpu_supports("avx2")},
        {"bmi1", __builtin_cpu_supports("bmi")},
        {"bmi2", __builtin_cpu_supports("bmi2")},
        {"fma", __builtin_cpu_supports("fma")},
        {"f16c", __builtin_cpu_supports("f16c")},
        {"lzcnt", __builtin_cpu_supports("lzcnt")},
        {"movbe", __builtin_cpu_supports("movbe")},
        {"xsave", __builtin_cpu_supports("xsave")},
        {"avx512f", __builtin_cpu_supports("avx512f")},
        {"avx512cd", __builtin_cpu_supports("avx512cd")},
        {"avx512bw", __builtin_cpu_supports("avx512bw")},
        {"avx512dq", __builtin_cpu_supports("avx512dq")},
        {"avx512vl", __builtin_cpu_supports("avx512vl")},
        {"adx", __builtin_cpu_supports("adx")},
        {"aes", __builtin_cpu_supports("aes")},
        {"pclmulqdq", __builtin_cpu_supports("pclmul")},
        {"rdrand", __builtin_cpu_supports("rdrnd")},
        {"rdseed", __builtin_cpu_supports("rdseed")},
        {"sha", __builtin_cpu_supports("sha")},
        {"xsavec", __builtin_cpu_supports("xsavec")},
        {"xsaveopt", __builtin_cpu_supports("xsaveopt")},
        {"xsaves", __builtin_cpu_supports("xsaves")},
        {"sse4a", __builtin_cpu_supports("sse4a")},
        {"tbm", __builtin_cpu_supports("tbm")},
        {"rtm", __builtin_cpu_supports("rtm")},
        {"gfni", __builtin_cpu_supports("gfni")},
        {"vaes", __builtin_cpu_supports("vaes")},
        {"vpclmulqdq", __builtin_cpu_supports("vpclmulqdq")},
        {"avx512ifma", __builtin_cpu_supports("avx512ifma")},
        {"avx512vbmi", __builtin_cpu_supports("avx512vbmi")},
        {"avx512vbmi2", __builtin_cpu_supports("avx512vbmi2")},
        {"avx512vnni", __builtin_cpu_supports("avx512vnni")},
        {"avx512bitalg", __builtin_cpu_supports("avx512bitalg")},
        {"avx512vpopcntdq", __builtin_cpu_supports("avx512vpopcntdq")},
        {"avx512bf16", __builtin_cpu_supports("avx512bf16")},
        {"avx512fp16", __builtin_cpu_supports("avx512fp16")},
        {"avx512vp2intersect", __builtin_cpu_supports("avx512vp2intersect")},
        {"avxvnni", __builtin_cpu_supports("avxvnni")},
        {"kl", __builtin_cpu_supports("kl")},
        {"widekl", __builtin_cpu_supports("widekl")},
    };
    char missing[1024] = ""; /* every name of the table fits */
    for (size_t i = 0; i < sizeof features / sizeof features[0]; i++) {
        if (features[i].present || !listed(P3TRACE_TARGET_FEATURES, features[i].name))
            continue;
        if (missing[0])
            strcat(missing, ", ");
        strcat(missing, features[i].name);
    }
    if (!missing[0])
        return;
    fprintf(stderr,
            "p3trace: error: this CPU lacks %s, which this binary was compiled to use "
            "(target-cpu %s); build it on this CPU (cargo build --release builds for the "
            "CPU it runs on), or build the portable binary with "
            "RUSTFLAGS='-C target-cpu=x86-64-v3' (docs/usage.md#install)\n",
            missing, P3TRACE_TARGET_CPU);
    exit(1);
}
