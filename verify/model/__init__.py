"""verify.model.system"""
