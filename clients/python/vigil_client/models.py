"""Every request and response model of the API (generated from the OpenAPI document)."""

from .generated.models import *  # noqa: F403
from .generated.models import __all__  # noqa: F401
