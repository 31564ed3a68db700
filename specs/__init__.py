"""The normative specifications, shipped as package data so that `verify explain CODE` can show them."""
