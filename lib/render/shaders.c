/* Shader library: GLSL sources embedded at build time (cmake/embed_shaders.cmake)
 * compiled into programs, with a one-level #include. */
#include "gpu_internal.h"

#include <stdlib.h>
#include <string.h>

typedef struct { const char *name; const char *src; } mr_shader_file;
extern const mr_shader_file mr_shader_files[];

const char *mr_shader_source(const char *name) {
    for (const mr_shader_file *f = mr_shader_files; f->name; f++)
        if (strcmp(f->name, name) == 0) return f->src;
    return NULL;
}

/* Appends s[0..n) to a growing buffer. */
static bool append(char **buf, size_t *len, size_t *cap, const char *s, size_t n) {
    if (*len + n + 1 > *cap) {
        size_t c = *cap ? *cap * 2 : 4096;
        while (c < *len + n + 1) c *= 2;
        char *p = realloc(*buf, c);
        if (!p) return false;
        *buf = p;
        *cap = c;
    }
    memcpy(*buf + *len, s, n);
    *len += n;
    (*buf)[*len] = 0;
    return true;
}

/* Expands `#include "file"` lines (one level: included files may not
 * include) and prepends the version line. */
static char *expand(const char *name, mr_error *err) {
    const char *src = mr_shader_source(name);
    if (!src) {
        mr_fail(err, MR_ERR_GL, "shader %s is not embedded", name);
        return NULL;
    }
    char *buf = NULL;
    size_t len = 0, cap = 0;
    static const char version[] = "#version 450 core\n";
    bool ok = append(&buf, &len, &cap, version, sizeof version - 1);
    for (const char *line = src; ok && *line;) {
        const char *end = strchr(line, '\n');
        size_t n = end ? (size_t)(end - line) + 1 : strlen(line);
        const char *inc = "#include \"";
        if (strncmp(line, inc, strlen(inc)) == 0) {
            char iname[128];
            const char *q = line + strlen(inc);
            const char *qe = memchr(q, '"', n - strlen(inc));
            size_t in = qe ? (size_t)(qe - q) : 0;
            if (!qe || in == 0 || in >= sizeof iname) {
                free(buf);
                mr_fail(err, MR_ERR_GL, "%s: malformed #include", name);
                return NULL;
            }
            memcpy(iname, q, in);
            iname[in] = 0;
            const char *isrc = mr_shader_source(iname);
            if (!isrc) {
                free(buf);
                mr_fail(err, MR_ERR_GL, "%s: included shader %s is not embedded", name, iname);
                return NULL;
            }
            ok = append(&buf, &len, &cap, isrc, strlen(isrc)) && append(&buf, &len, &cap, "\n", 1);
        } else {
            ok = append(&buf, &len, &cap, line, n);
        }
        line += n;
    }
    if (!ok) {
        free(buf);
        mr_fail(err, MR_ERR_NOMEM, "out of memory building shader %s", name);
        return NULL;
    }
    return buf;
}

static GLenum stage_of(const char *name) {
    if (strstr(name, ".vert.")) return GL_VERTEX_SHADER;
    if (strstr(name, ".frag.")) return GL_FRAGMENT_SHADER;
    if (strstr(name, ".comp.")) return GL_COMPUTE_SHADER;
    if (strstr(name, ".geom.")) return GL_GEOMETRY_SHADER;
    return 0;
}

GLuint mr_gl_program(const char *const *files, mr_error *err) {
    GLuint prog = glCreateProgram();
    GLuint shaders[8];
    int ns = 0;
    bool ok = true;
    for (int i = 0; ok && files[i] && ns < 8; i++) {
        GLenum stage = stage_of(files[i]);
        char *src = stage ? expand(files[i], err) : NULL;
        if (!stage) mr_fail(err, MR_ERR_GL, "cannot tell the stage of shader %s", files[i]);
        if (!src) { ok = false; break; }
        GLuint sh = glCreateShader(stage);
        const char *s = src;
        glShaderSource(sh, 1, &s, NULL);
        glCompileShader(sh);
        free(src);
        GLint status = 0;
        glGetShaderiv(sh, GL_COMPILE_STATUS, &status);
        if (!status) {
            char log[1024] = "";
            glGetShaderInfoLog(sh, sizeof log, NULL, log);
            mr_fail(err, MR_ERR_GL, "shader %s does not compile: %s", files[i], log);
            glDeleteShader(sh);
            ok = false;
            break;
        }
        glAttachShader(prog, sh);
        shaders[ns++] = sh;
    }
    if (ok) {
        glLinkProgram(prog);
        GLint status = 0;
        glGetProgramiv(prog, GL_LINK_STATUS, &status);
        if (!status) {
            char log[1024] = "";
            glGetProgramInfoLog(prog, sizeof log, NULL, log);
            mr_fail(err, MR_ERR_GL, "program %s does not link: %s", files[0], log);
            ok = false;
        }
    }
    for (int i = 0; i < ns; i++) {
        glDetachShader(prog, shaders[i]);
        glDeleteShader(shaders[i]);
    }
    if (!ok) {
        glDeleteProgram(prog);
        return 0;
    }
    return prog;
}

uint32_t mr_gpu_program(const char *const *files, mr_error *err) { return mr_gl_program(files, err); }
