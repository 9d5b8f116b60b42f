"""Reader of procman sheriff configs (.pmd) for procman/run-local.

The libbot2 procman grammar: `cmd "name" { attr = value; ... }`, `group "name" { cmd ... group ... }`,
`script "name" { actions; }` with the attributes exec, host, auto_respawn, group, stop_signal and
stop_time_allowed (the standalone procman's `deputy` is accepted as a synonym of `host`), '#'
comments, and `# @default NAME = "value";` comment lines for run-local's variable defaults. Errors
name the file and line. Variables in exec words are expanded like procman's deputy does ($NAME and
${NAME} inside each word of the shell-split command line).
"""

import os
import re
import shlex

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ATTRS = {"exec": str, "host": str, "deputy": str, "auto_respawn": str, "group": str,
         "stop_signal": int, "stop_time_allowed": int}


class PmdError(Exception):
    pass


# ---------------------------------------------------------------- parsing

def tokenize(text, path):
    """Yields (kind, value, line): kind in ident, string, int, and the characters { } = ;"""
    i, line, n = 0, 1, len(text)
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
            i += 1
        elif c.isspace():
            i += 1
        elif c == "#":
            while i < n and text[i] != "\n":
                i += 1
        elif c in "{}=;":
            yield (c, c, line)
            i += 1
        elif c == '"':
            i += 1
            out = []
            while True:
                if i >= n or text[i] == "\n":
                    raise PmdError("%s:%d: unterminated string" % (path, line))
                if text[i] == "\\" and i + 1 < n:
                    out.append({"n": "\n", "t": "\t", "r": "\r"}.get(text[i + 1], text[i + 1]))
                    i += 2
                elif text[i] == '"':
                    i += 1
                    break
                else:
                    out.append(text[i])
                    i += 1
            yield ("string", "".join(out), line)
        elif c.isalpha() or c == "_":
            j = i
            while j < n and (text[j].isalnum() or text[j] in "_-"):
                j += 1
            yield ("ident", text[i:j], line)
            i = j
        elif c.isdigit():
            j = i
            while j < n and text[j].isdigit():
                j += 1
            yield ("int", int(text[i:j]), line)
            i = j
        else:
            raise PmdError("%s:%d: unexpected character %r" % (path, line, c))
    yield ("eof", "", line)


class Command:
    def __init__(self, name, group, line):
        self.name, self.group, self.line = name, group, line
        self.attrs = {}

    @property
    def host(self):
        return self.attrs.get("host", self.attrs.get("deputy", ""))


class Config:
    def __init__(self, path):
        self.path = path
        self.commands = []   # in file order
        self.groups = {}     # "outer/inner" -> [Command] (nested groups included)
        self.scripts = {}    # name -> [action tuples]
        self.defaults = {}   # from "# @default NAME = "value";" lines
        with open(path) as f:
            text = f.read()
        for ln, raw in enumerate(text.splitlines(), 1):
            m = re.match(r'\s*#\s*@default\s+([A-Za-z_][A-Za-z0-9_]*)\s*=\s*"([^"]*)"\s*;?\s*$', raw)
            if m:
                self.defaults[m.group(1)] = m.group(2)
            elif re.match(r"\s*#\s*@default\b", raw):
                raise PmdError('%s:%d: malformed @default line (expected: # @default NAME = "value";)' % (path, ln))
        self.toks = list(tokenize(text, path))
        self.pos = 0
        while self.peek()[0] != "eof":
            kind = self.expect_ident(("cmd", "group", "script"))
            if kind == "cmd":
                self.parse_cmd([])
            elif kind == "group":
                self.parse_group([])
            else:
                self.parse_script()
        names = [c.name for c in self.commands]
        for c in self.commands:
            if names.count(c.name) > 1:
                raise PmdError('%s:%d: command name "%s" is used twice' % (path, c.line, c.name))

    def peek(self):
        return self.toks[self.pos]

    def next(self):
        t = self.toks[self.pos]
        self.pos += 1
        return t

    def fail(self, msg, tok=None):
        tok = tok or self.peek()
        raise PmdError("%s:%d: %s (at %s)" % (self.path, tok[2], msg, repr(tok[1]) if tok[0] != "eof" else "end of file"))

    def expect(self, kind, what):
        t = self.next()
        if t[0] != kind:
            self.fail("expected " + what, t)
        return t[1]

    def expect_ident(self, allowed):
        t = self.next()
        if t[0] != "ident" or t[1] not in allowed:
            self.fail("expected one of " + ", ".join(allowed), t)
        return t[1]

    def parse_cmd(self, group_path):
        line = self.peek()[2]
        name = self.expect("string", "a command name in double quotes")
        if "/" in name or not name.strip():
            self.fail("invalid command name")
        cmd = Command(name, "/".join(group_path), line)
        self.expect("{", "'{'")
        while self.peek()[0] == "ident":
            t = self.next()
            if t[1] not in ATTRS:
                self.fail("unknown attribute '%s' of cmd \"%s\" (known: %s)" % (t[1], name, ", ".join(ATTRS)), t)
            self.expect("=", "'='")
            v = self.next()
            if ATTRS[t[1]] is str and v[0] != "string":
                self.fail("attribute %s needs a string in double quotes" % t[1], v)
            if ATTRS[t[1]] is int and v[0] != "int":
                self.fail("attribute %s needs an integer" % t[1], v)
            cmd.attrs[t[1]] = v[1]
            self.expect(";", "';'")
        self.expect("}", "'}' or an attribute")
        if not cmd.attrs.get("exec"):
            raise PmdError('%s:%d: cmd "%s" has no exec' % (self.path, line, name))
        if cmd.attrs.get("auto_respawn", "false") not in ("true", "false"):
            raise PmdError('%s:%d: cmd "%s": auto_respawn must be "true" or "false"' % (self.path, line, name))
        self.commands.append(cmd)
        for k in range(1, len(group_path) + 1):
            self.groups.setdefault("/".join(group_path[:k]), []).append(cmd)

    def parse_group(self, group_path):
        name = self.expect("string", "a group name in double quotes")
        if "/" in name or not name.strip():
            self.fail("invalid group name")
        path = group_path + [name]
        self.groups.setdefault("/".join(path), [])
        self.expect("{", "'{'")
        while self.peek()[0] == "ident":
            if self.expect_ident(("cmd", "group")) == "cmd":
                self.parse_cmd(path)
            else:
                self.parse_group(path)
        self.expect("}", "'}', cmd or group")

    def parse_script(self):
        name = self.expect("string", "a script name in double quotes")
        actions = []
        self.expect("{", "'{'")
        while self.peek()[0] == "ident":
            line = self.peek()[2]
            act = self.expect_ident(("start", "stop", "restart", "wait", "run_script"))
            if act in ("start", "stop", "restart"):
                kind = self.expect_ident(("everything", "cmd", "group"))
                target = None if kind == "everything" else self.expect("string", "a name in double quotes")
                wait = None
                if self.peek()[0] == "ident":
                    self.expect_ident(("wait",))
                    wait = self.expect("string", '"running" or "stopped"')
                    if wait not in ("running", "stopped"):
                        self.fail('expected "running" or "stopped"')
                actions.append((act, kind, target, wait, line))
            elif act == "wait":
                kind = self.expect_ident(("ms", "cmd", "group"))
                if kind == "ms":
                    actions.append(("wait_ms", self.expect("int", "milliseconds"), line))
                else:
                    target = self.expect("string", "a name in double quotes")
                    self.expect_ident(("status",))
                    status = self.expect("string", '"running" or "stopped"')
                    if status not in ("running", "stopped"):
                        self.fail('expected "running" or "stopped"')
                    actions.append(("wait_status", kind, target, status, line))
            else:
                actions.append(("run_script", self.expect("string", "a script name"), line))
            self.expect(";", "';'")
        self.expect("}", "'}' or an action")
        if name in self.scripts:
            self.fail('script "%s" defined twice' % name)
        self.scripts[name] = actions

    def targets(self, kind, name, line=None):
        where = "%s:%d: " % (self.path, line) if line else ""
        if kind == "everything":
            return list(self.commands)
        if kind == "cmd":
            found = [c for c in self.commands if c.name == name]
            if not found:
                raise PmdError('%sno cmd "%s" in %s' % (where, name, self.path))
            return found
        if name not in self.groups:
            raise PmdError('%sno group "%s" in %s (groups: %s)' % (where, name, self.path, ", ".join(sorted(self.groups))))
        return list(self.groups[name])


# ---------------------------------------------------------------- variables

VAR_RE = re.compile(r"\$\{([A-Za-z_][A-Za-z0-9_]*)\}|\$([A-Za-z_][A-Za-z0-9_]*)")


def expand(word, lookup, cmd):
    def sub(m):
        name = m.group(1) or m.group(2)
        val = lookup(name, set())
        if val is None:
            raise PmdError('cmd "%s": variable %s is not set (use --var %s=... or export it)' % (cmd.name, name, name))
        return val
    return VAR_RE.sub(sub, word)


def make_lookup(cfg, cli_vars):
    def lookup(name, seen):
        if name in cli_vars:
            return cli_vars[name]
        if name in os.environ:
            return os.environ[name]
        if name == "LIVO_ROOT":
            return ROOT
        if name in cfg.defaults:
            if name in seen:
                raise PmdError("@default %s refers to itself" % name)
            return VAR_RE.sub(lambda m: lookup(m.group(1) or m.group(2), seen | {name}) or m.group(0),
                              cfg.defaults[name])
        return None
    return lookup


def command_line(cmd, lookup):
    """(argv, extra environment) of a command, as procman's deputy would run it."""
    try:
        words = shlex.split(cmd.attrs["exec"])
    except ValueError as e:
        raise PmdError('cmd "%s": cannot split exec: %s' % (cmd.name, e))
    env = {}
    while words and re.match(r"[A-Za-z_][A-Za-z0-9_]*=", words[0]):
        k, v = words.pop(0).split("=", 1)
        env[k] = expand(v, lookup, cmd)
    if not words:
        raise PmdError('cmd "%s": exec has no program' % cmd.name)
    return [expand(w, lookup, cmd) for w in words], env


def script_uses(cfg, name, cmd, depth=0):
    """True when the script (or one it runs) names cmd, its group or everything."""
    if depth > 16 or name not in cfg.scripts:
        return False
    for act in cfg.scripts[name]:
        if act[0] in ("start", "stop", "restart"):
            kind, target = act[1], act[2]
            if kind == "everything" or (kind == "cmd" and target == cmd.name) or \
               (kind == "group" and cmd in cfg.groups.get(target, [])):
                return True
        elif act[0] == "run_script" and script_uses(cfg, act[1], cmd, depth + 1):
            return True
    return False
