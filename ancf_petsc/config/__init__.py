"""Input layer: a YAML config → a validated ``ModelSpec`` whose errors name the key path and the fix.

``load_config(path)`` / ``parse_config(raw)`` (parse.py) are the entry points; the spec types are in
specs.py, the value checks in values.py, and each part of a config has its own module.
"""
from .parse import load_config, parse_config
from .specs import ModelSpec
from .values import ConfigError

__all__ = ["ConfigError", "ModelSpec", "load_config", "parse_config"]
