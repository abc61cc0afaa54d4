"""mbcontact: preprocessing tools for the mbcontact multibody contact solver."""

__version__ = "0.1.0"
