"""verify.frontend"""
