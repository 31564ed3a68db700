"""verify.core"""
