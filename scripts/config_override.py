#!/usr/bin/env python3
"""An estimator config with SECTION.KEY=VALUE overrides (VALUE read as YAML), for the experiment scripts.

  scripts/config_override.py IN.yaml OUT.yaml [SECTION.KEY=VALUE ...]

Importable: apply_overrides(cfg, ["update.sigma_px=0.5", ...]) changes the dict in place and returns it.
"""
import sys

import yaml


def apply_overrides(cfg, overrides):
    for kv in overrides:
        key, sep, value = kv.partition("=")
        section, dot, k = key.partition(".")
        if not sep or not dot:
            raise SystemExit(f"config override '{kv}': expected SECTION.KEY=VALUE")
        cfg.setdefault(section, {})[k] = yaml.safe_load(value)
    return cfg


def main():
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    cfg = yaml.safe_load(open(sys.argv[1])) or {}
    yaml.safe_dump(apply_overrides(cfg, sys.argv[3:]), open(sys.argv[2], "w"), sort_keys=False)


if __name__ == "__main__":
    main()
