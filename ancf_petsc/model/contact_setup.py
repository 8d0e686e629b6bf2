"""Contact for a model, with the contact layer's setup errors named by their config keys
(``contact`` or ``contact.interfaces[k]``): the boundary between the config and the contact code."""
from __future__ import annotations

from ..config.specs import ContactSpec
from ..config.values import ConfigError
from ..contact import Contact, ContactSetupError, build_contact
from .beams import Model
from .build import build_model


def contact_for(model: Model, spec: ContactSpec, log=print) -> Contact:
    """``contact.build_contact``; a ContactSetupError becomes a ConfigError naming the key."""
    try:
        return build_contact(model, spec, log)
    except ContactSetupError as exc:
        key = exc.key or ("contact" if exc.interface is None else f"contact.interfaces[{exc.interface}]")
        raise ConfigError(key, str(exc)) from None


def check_model(spec) -> Model:
    """The model of ``spec`` and its contact built once, for their input checks (a ConfigError
    names the key): what a run checks before it solves."""
    model = build_model(spec)
    if spec.contact:                    # the interfaces' checks (conforming meshes, sides)
        contact_for(model, spec.contact, lambda *_: None)
    return model
